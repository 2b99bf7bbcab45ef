#pragma once
// Reading volume meshes (DESIGN.md io/): TetGen .node/.ele, MEDIT .mesh, Gmsh .msh 2.2 and 4.1 (ASCII),
// and VTK .vtu (ASCII data), with tets or hexes; then checking them. Every problem is one line naming
// the file and the line (or the element) at fault.
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// A mesh file that cannot be used: "FILE:LINE: what is wrong" (or "FILE: element N: ...").
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MeshFile {
  VolumeMesh mesh;
  std::vector<int> cell_lines;  ///< the line each cell was read from (0 where not known)
  int reoriented = 0;           ///< inverted rest elements turned the right way round by check_mesh
};

/// Reads a mesh by its extension (.node or .ele: both files of the pair; .mesh; .msh; .vtu), without the
/// geometric checks. Throws MeshError.
[[nodiscard]] MeshFile read_mesh_file(const std::filesystem::path& path);

/// Checks a mesh read from `file`: finite coordinates, indices in range and not repeated within a cell,
/// no unreferenced vertex, no degenerate cell (|volume| below 1e-10 of the mean cell volume); cells with
/// negative rest volume are re-oriented (counted in `reoriented`). Throws MeshError.
void check_mesh(MeshFile& m, const std::filesystem::path& file);

/// A .vtu file's mesh (unchecked, as read_mesh_file) and its named data arrays, e.g. a frame written by
/// write_vtu read back. Values are interleaved by component (x0 y0 z0 x1 ...); cell arrays hold the
/// values of the tet and hex cells only (surface, line and vertex cells are skipped, as in the mesh).
struct VtuData {
  MeshFile mesh;
  std::map<std::string, std::vector<double>> point_data, cell_data;
};

/// Reads a .vtu file with its <PointData> and <CellData> arrays. Throws MeshError.
[[nodiscard]] VtuData read_vtu_data(const std::filesystem::path& path);

/// read_mesh_file + check_mesh.
[[nodiscard]] MeshFile read_mesh(const std::filesystem::path& path);

}  // namespace snh
