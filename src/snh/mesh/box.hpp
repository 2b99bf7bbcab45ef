#pragma once
// The paper's box meshes (docs/paper-programs.md): a (res+1)³ lattice on [−1, 1]³.
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Index of lattice vertex (i, j, k): i + j (res+1) + k (res+1)².
[[nodiscard]] constexpr int lattice_index(int res, int i, int j, int k) {
  return i + j * (res + 1) + k * (res + 1) * (res + 1);
}

/// The (res+1)³ lattice vertices at (−1,−1,−1) + (2/res)(i, j, k), in lattice_index order.
[[nodiscard]] Eigen::Matrix3Xd box_lattice(int res);

/// res³ hexahedra, cell (i, j, k) with corners c0..c7 as in VolumeMesh (hexcli's mesh).
///   res  cells per side, ≥ 1
[[nodiscard]] VolumeMesh box_hexes(int res);

/// How box_tets cuts each lattice cell into six tets.
enum class TetSplit {
  paper,     ///< every cell around its c0–c7 diagonal (tetcli's mesh): symmetric under central
             ///< inversion and x↔z exchange, but not under a mirror in one axis
  mirrored,  ///< cells in the upper half along an axis use the template mirrored in that axis: for even
             ///< res the mesh is mirror symmetric in x, y and z (still conforming)
};

/// 6 res³ tetrahedra: each lattice cell cut around its c0–c7 diagonal with the corner templates
/// {7,4,0,5} {7,6,0,4} {7,5,0,1} {7,2,0,6} {7,1,0,3} {7,3,0,2}; a tet with negative rest volume gets its
/// last two vertices swapped (tetcli's mesh). Cells in lattice order, six per cell in template order.
/// With TetSplit::mirrored, a cell (i, j, k) with 2i ≥ res (likewise j, k) exchanges its corners
/// across the x mid-plane (c ↦ c xor 1; y: xor 2, z: xor 4) before the templates apply.
[[nodiscard]] VolumeMesh box_tets(int res, TetSplit split = TetSplit::paper);

}  // namespace snh
