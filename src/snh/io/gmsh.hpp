#pragma once
// Gmsh .msh (DESIGN.md io/): versions 2.2 and 4.1, ASCII or binary (little-endian, data size 8), with
// 4-node tetrahedra or 8-node hexahedra; points, lines, triangles and quadrangles are skipped.
#include <filesystem>

#include "snh/io/mesh_file.hpp"

namespace snh {

/// Reads a Gmsh mesh, without the geometric checks (check_mesh).
///   path  the .msh file; sections other than $Nodes and $Elements (also binary ones) are skipped
/// Returns the mesh with each cell's line (in a binary file, the line its section's data starts on).
/// Throws MeshError ("FILE:LINE: ..."), also for prisms, pyramids and parametric nodes.
[[nodiscard]] MeshFile read_gmsh(const std::filesystem::path& path);

}  // namespace snh
