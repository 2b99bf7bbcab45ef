#pragma once
// Reading volume meshes (docs/design.md) by extension: TetGen .node/.ele (io/tetgen), MEDIT .mesh
// (io/medit), Gmsh .msh 2.2 and 4.1 (io/gmsh), VTK .vtu (io/vtu), and closed surfaces tetrahedralized
// (io/surface_read), with tets or hexes; then checking them (io/mesh_check). Every problem is one line
// naming the file and the line (or the element) at fault. Including this header brings MeshError,
// MeshFile, check_mesh, VtuData and read_vtu_data with it.
#include <filesystem>

#include "snh/io/mesh_check.hpp"
#include "snh/io/mesh_file.hpp"
#include "snh/io/vtu.hpp"

namespace snh {

/// Reads a mesh by its extension (.node or .ele: both files of the pair; .mesh; .msh; .vtu; a surface
/// .obj, .off, .ply or .stl through tetgen), without the geometric checks. Throws MeshError.
[[nodiscard]] MeshFile read_mesh_file(const std::filesystem::path& path);

/// read_mesh_file + check_mesh.
[[nodiscard]] MeshFile read_mesh(const std::filesystem::path& path);

}  // namespace snh
