#pragma once
// A hexahedral lattice embedding a closed surface (docs/design.md), as the paper's Figure 1: the cubes of
// a regular grid that overlap the solid, i.e. every cube a surface triangle passes through (an exact
// triangle-box overlap test) and every cube wholly inside (the winding number at its centre, asked once per
// connected region of cubes the surface does not touch).
#include <vector>

#include <Eigen/Core>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

struct Lattice {
  VolumeMesh mesh;            ///< hex8 cells in VolumeMesh corner order; only the vertices the cells use
  Eigen::Vector3d origin;     ///< the grid's lowest corner
  double spacing = 0.0;       ///< the cubes' edge length
  Eigen::Vector3i dims;       ///< cubes along x, y, z
  std::vector<int> cell_at;   ///< dims.prod(): the cell of cube (i, j, k) at i + dims.x · (j + dims.y · k), or −1
  [[nodiscard]] int cube_index(int i, int j, int k) const { return i + dims.x() * (j + dims.y() * k); }
  /// A point in cube units: cube (i, j, k) spans [i, i+1] × [j, j+1] × [k, k+1]. The lattice is built and
  /// points are embedded with this one expression, so a surface vertex finds the cubes its triangles marked.
  [[nodiscard]] Eigen::Vector3d grid_coordinates(const Eigen::Vector3d& p) const { return (p - origin) / spacing; }
};

/// The lattice of a surface with `resolution` cubes along the bounding box's longest side (the grid padded by
/// a small fraction of a cube so no surface point lies on its outer faces). A cube is kept when a triangle
/// overlaps it (separating axes, the cube grown by 1e-9 of its edge so a point on a shared face counts for
/// the cubes on both sides) or when its centre is inside: |winding number| > ½, so either orientation, and
/// overlapping parts, count (Jacobson et al. 2013's generalized winding number: holes tolerated). On a closed
/// surface the winding number is asked once per region of untouched cubes (face neighbours), on an open one
/// at every untouched cube. Cells and vertices are numbered in grid order (x fastest).
/// Throws std::invalid_argument for resolution < 1, a non-finite vertex, an index out of range, no
/// triangles, a surface with no extent, or a grid of more than 2^28 cubes.
///   V  3 by #V (the bounding box is that of the vertices F uses);  F  3 by #F (a closed surface, or a soup)
[[nodiscard]] Lattice lattice_for_surface(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution);

}  // namespace snh
