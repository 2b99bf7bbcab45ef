#pragma once
// Writing volume meshes (docs/design.md) by extension: Gmsh .msh 4.1 ASCII (io/gmsh), VTK .vtu (io/vtu)
// and MEDIT .mesh (io/medit); each file written atomically. Including this header brings write_msh and
// write_medit with it.
#include <filesystem>

#include "snh/io/gmsh.hpp"
#include "snh/io/medit.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Throws std::invalid_argument (one line) unless write_mesh can write `path`'s extension.
void check_writable_mesh_format(const std::filesystem::path& path);
/// By extension: .msh, .vtu or .mesh. Throws std::invalid_argument for another extension.
void write_mesh(const std::filesystem::path& path, const VolumeMesh& mesh);

}  // namespace snh
