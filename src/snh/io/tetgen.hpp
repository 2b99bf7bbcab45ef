#pragma once
// TetGen's .node / .ele pair (docs/design.md): linear tetrahedra, '#' comments, any first index.
#include <filesystem>

#include "snh/io/mesh_file.hpp"

namespace snh {

/// Reads a TetGen mesh, without the geometric checks (check_mesh).
///   node_path  the .node file: #V, dimension 3, #attributes, marker flag; then id x y z (attributes, marker)
///   ele_path   the .ele file: #C, 4 nodes per tet, region flag; then id and 4 vertex ids (region)
/// Returns the mesh with each cell's line in the .ele file. Throws MeshError ("FILE:LINE: ...").
[[nodiscard]] MeshFile read_tetgen(const std::filesystem::path& node_path, const std::filesystem::path& ele_path);

}  // namespace snh
