#pragma once
// Gmsh .msh (docs/design.md): read in versions 2.2 and 4.1, ASCII or binary (little-endian, data size 8),
// with 4-node tetrahedra or 8-node hexahedra (points, lines, triangles and quadrangles are skipped);
// written as 4.1 ASCII.
#include <filesystem>

#include "snh/io/mesh_file.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Reads a Gmsh mesh, without the geometric checks (check_mesh).
///   path  the .msh file; sections other than $Nodes and $Elements (also binary ones) are skipped
/// Returns the mesh with each cell's line (in a binary file, the line its section's data starts on).
/// Throws MeshError ("FILE:LINE: ..."), also for prisms, pyramids and parametric nodes.
[[nodiscard]] MeshFile read_gmsh(const std::filesystem::path& path);

/// Writes Gmsh 4.1 ASCII atomically: one volume entity, 4-node tets (type 4) or 8-node hexes (type 5),
/// 1-based tags, coordinates to 17 significant digits.
///   path  output file (.msh)
///   mesh  the mesh (hexahedra written in Gmsh's corner order)
void write_msh(const std::filesystem::path& path, const VolumeMesh& mesh);

}  // namespace snh
