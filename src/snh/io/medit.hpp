#pragma once
// MEDIT .mesh (DESIGN.md io/): MeshVersionFormatted 1 or 2, Dimension 3, Vertices and Tetrahedra or
// Hexahedra; the surface and other sections are skipped.
#include <filesystem>

#include "snh/io/mesh_file.hpp"

namespace snh {

/// Reads a MEDIT mesh, without the geometric checks (check_mesh).
///   path  the .mesh file ('#' comments; indices 1-based; hexahedra in MEDIT's corner order)
/// Returns the mesh with each cell's line. Throws MeshError ("FILE:LINE: ...").
[[nodiscard]] MeshFile read_medit(const std::filesystem::path& path);

}  // namespace snh
