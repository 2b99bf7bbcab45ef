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

}  // namespace snh
