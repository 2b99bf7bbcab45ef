#pragma once
// VTK XML unstructured grids (.vtu) and ParaView series (.pvd) (DESIGN.md io/): frames of a volume mesh
// written (ASCII data), and .vtu meshes read back with their data arrays (ASCII, inline base64, or
// appended raw or base64 data; uncompressed, little-endian).
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/io/mesh_file.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Writes one frame atomically.
///   path         output file (.vtu)
///   mesh         cells (tet4 or hex8, VolumeMesh corner order; written in VTK's order)
///   positions    3 by #V deformed positions
///   point_data   named 3-vector fields, each 3 by #V (e.g. "displacement")
///   cell_data    named scalar fields, each #C (e.g. "J"); non-finite values are written as inf / nan
///   point_scalars named scalar fields, each #V (e.g. "pinned")
void write_vtu(const std::filesystem::path& path, const VolumeMesh& mesh, const Eigen::Matrix3Xd& positions,
               const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars = {});

/// Writes a ParaView collection listing (time, file) pairs; files relative to the .pvd's directory.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& frames);

/// Reads a ParaView collection back: (time, file) of each DataSet in order (a missing timestep is the
/// DataSet's index). Throws MeshError ("FILE: what is wrong") for an unreadable file, a DataSet without
/// a file or with a timestep that is not a number, or no DataSet at all.
[[nodiscard]] std::vector<std::pair<double, std::string>> read_pvd(const std::filesystem::path& path);

/// Reads a .vtu file's mesh, without the geometric checks (check_mesh).
///   path  the .vtu file: one <Piece>; tet (VTK type 10) and hex (12) cells are kept, surface, line and
///         vertex cells (5, 9, 3, 1) skipped
/// Returns the mesh (cell lines unknown: 0). Throws MeshError ("FILE:LINE: ...").
[[nodiscard]] MeshFile read_vtu(const std::filesystem::path& path);

/// A .vtu file's mesh (unchecked, as read_mesh_file) and its named data arrays, e.g. a frame written by
/// write_vtu read back. Values are interleaved by component (x0 y0 z0 x1 ...); cell arrays hold the
/// values of the tet and hex cells only (surface, line and vertex cells are skipped, as in the mesh).
struct VtuData {
  MeshFile mesh;
  std::map<std::string, std::vector<double>> point_data, cell_data;
};

/// Reads a .vtu file with its <PointData> and <CellData> arrays. Throws MeshError.
[[nodiscard]] VtuData read_vtu_data(const std::filesystem::path& path);

}  // namespace snh
