#pragma once
// MEDIT .mesh (docs/design.md): MeshVersionFormatted 1 or 2, Dimension 3, Vertices and Tetrahedra or
// Hexahedra; read with the surface and other sections skipped, written as version 2.
#include <filesystem>

#include "snh/io/mesh_file.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Reads a MEDIT mesh, without the geometric checks (check_mesh).
///   path  the .mesh file ('#' comments; indices 1-based; hexahedra in MEDIT's corner order)
/// Returns the mesh with each cell's line. Throws MeshError ("FILE:LINE: ...").
[[nodiscard]] MeshFile read_medit(const std::filesystem::path& path);

/// Writes MEDIT (MeshVersionFormatted 2) atomically: Vertices and Tetrahedra or Hexahedra, references 0,
/// coordinates to 17 significant digits.
///   path  output file (.mesh)
///   mesh  the mesh (hexahedra written in MEDIT's corner order)
void write_medit(const std::filesystem::path& path, const VolumeMesh& mesh);

}  // namespace snh
