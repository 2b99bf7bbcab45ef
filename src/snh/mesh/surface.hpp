#pragma once
// Boundary surface of a volume mesh.
#include <vector>

#include <Eigen/Dense>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Outward-oriented triangles of the boundary: the cell faces that belong to one cell only, in cell
/// order then local face order. A boundary quad of a hex gives two triangles (a,b,c), (a,c,d).
///   mesh    tets with positive rest volume, or hexes in the VolumeMesh corner order
///   cells   if not null, receives the cell of each triangle (#F)
/// Returns 3 by #F vertex indices (0-based).
[[nodiscard]] Eigen::Matrix3Xi boundary_triangles(const VolumeMesh& mesh, std::vector<int>* cells = nullptr);

/// How a triangle surface's edges are shared: a closed, manifold surface has every edge in exactly two
/// triangles.
struct EdgeCounts {
  int edges = 0;         ///< distinct undirected edges
  int open = 0;          ///< in one triangle only (a hole's rim)
  int non_manifold = 0;  ///< in three or more triangles
};
///   F  3 by #F vertex indices
[[nodiscard]] EdgeCounts edge_counts(const Eigen::Matrix3Xi& F);

}  // namespace snh
