#pragma once
// A volume mesh of tet4 or hex8 cells (docs/design.md). libigl-style: vertices 3 by #V, cells
// nodes-per-cell by #C (one column per cell).
#include <string_view>

#include <Eigen/Dense>

namespace snh {

enum class CellType { tet4, hex8 };

[[nodiscard]] constexpr int nodes_per_cell(CellType t) { return t == CellType::tet4 ? 4 : 8; }
[[nodiscard]] constexpr std::string_view to_string(CellType t) { return t == CellType::tet4 ? "tet4" : "hex8"; }

struct VolumeMesh {
  CellType type = CellType::tet4;
  Eigen::Matrix3Xd vertices;  ///< rest positions, 3 by #V
  Eigen::MatrixXi cells;      ///< vertex indices, nodes_per_cell(type) by #C
  /// Hex8 corner order (docs/paper-programs.md): c0 = (i,j,k), c1 = c0 + x̂, c2 = c0 + ŷ, c3 = c0 + x̂ + ŷ,
  /// c4..c7 = c0..c3 + ẑ. Tet4: any order with positive rest volume (det[x1−x0, x2−x0, x3−x0] > 0).

  [[nodiscard]] Eigen::Index vertex_count() const { return vertices.cols(); }
  [[nodiscard]] Eigen::Index cell_count() const { return cells.cols(); }
};

/// The signed rest volume of cell `c`: a tet's exactly; a hex's from the trilinear map's Jacobian at its
/// centre (corner order above), exact for parallelepipeds.
[[nodiscard]] double cell_volume(const VolumeMesh& m, Eigen::Index c);
/// Σ cell_volume over the cells, in cell order.
[[nodiscard]] double mesh_volume(const VolumeMesh& m);

}  // namespace snh
