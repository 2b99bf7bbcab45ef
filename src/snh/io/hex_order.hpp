#pragma once
// Internal to io/: hexahedron corners in files (VTK, Gmsh, MEDIT: the bottom face around, then the top)
// and in VolumeMesh (lattice order: c2 = c0 + ŷ, c3 = c0 + x̂ + ŷ).
#include <vector>

#include "snh/mesh/volume_mesh.hpp"

namespace snh::detail {

/// Swapping corners 2 ↔ 3 and 6 ↔ 7 maps either order to the other (the permutation is its own inverse).
inline constexpr int kHexCornerSwap[8] = {0, 1, 3, 2, 4, 5, 7, 6};

/// A hexahedron's 8 vertex ids from file order to lattice order.
inline std::vector<long long> hex_to_lattice(const std::vector<long long>& ids) {
  std::vector<long long> out(8);
  for (int a = 0; a < 8; ++a) out[a] = ids[kHexCornerSwap[a]];
  return out;
}

/// The VolumeMesh corner written as file corner `a` of a cell of type `t` (tets keep their order).
inline int file_corner(CellType t, int a) { return t == CellType::tet4 ? a : kHexCornerSwap[a]; }

}  // namespace snh::detail
