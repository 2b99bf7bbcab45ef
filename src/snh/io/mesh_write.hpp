#pragma once
// Writing volume meshes (DESIGN.md io/): Gmsh .msh 4.1 (ASCII), VTK .vtu and MEDIT .mesh, chosen by
// extension; each file written atomically.
#include <filesystem>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Gmsh 4.1 ASCII: one volume entity, 4-node tets (type 4) or 8-node hexes (type 5), 1-based tags.
void write_msh(const std::filesystem::path& path, const VolumeMesh& mesh);
/// MEDIT .mesh (MeshVersionFormatted 2): Vertices and Tetrahedra or Hexahedra, references 0.
void write_medit(const std::filesystem::path& path, const VolumeMesh& mesh);
/// Throws std::invalid_argument (one line) unless write_mesh can write `path`'s extension.
void check_writable_mesh_format(const std::filesystem::path& path);
/// By extension: .msh, .vtu or .mesh. Throws std::invalid_argument for another extension.
void write_mesh(const std::filesystem::path& path, const VolumeMesh& mesh);

}  // namespace snh
