#pragma once
// VTK XML unstructured grids (.vtu) and ParaView series (.pvd) (docs/design.md): frames of a volume mesh
// written (binary: the arrays appended raw after the XML, full double precision), and .vtu meshes read
// back with their data arrays (ASCII, inline base64, or appended raw or base64 data; uncompressed,
// little-endian).
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/io/mesh_file.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Writes the .vtu frames of one mesh: VTK XML (version 1.0, UInt64 length headers, little-endian), every
/// DataArray format="appended" with its offset into one <AppendedData encoding="raw"> block (each array:
/// its length in bytes as a UInt64, then its values). Points and fields are Float64, written bit for bit;
/// connectivity and offsets Int64, types UInt8. The cell arrays are made once, by the constructor; a frame
/// writes its header, then its arrays straight from the matrices.
class VtuWriter {
 public:
  /// mesh: cells (tet4 or hex8, VolumeMesh corner order; written in VTK's order).
  explicit VtuWriter(const VolumeMesh& mesh);
  /// Writes one frame atomically.
  ///   path          output file (.vtu)
  ///   positions     3 by #V deformed positions
  ///   point_data    named 3-vector fields, each 3 by #V (e.g. "displacement")
  ///   cell_data     named scalar fields, each #C (e.g. "J"); non-finite values are kept (IEEE inf / nan)
  ///   point_scalars named scalar fields, each #V (e.g. "pinned")
  /// Throws std::invalid_argument (naming the array) for an array of the wrong size, WriteError /
  /// OutputRefused as write_atomically.
  void write(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions,
             const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
             const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
             const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars = {}) const;

 private:
  Eigen::Index vertices_ = 0;
  std::vector<std::int64_t> connectivity_, offsets_;
  std::vector<std::uint8_t> types_;
};

/// Writes one frame atomically: VtuWriter(mesh).write(path, positions, point_data, cell_data, point_scalars).
void write_vtu(const std::filesystem::path& path, const VolumeMesh& mesh, const Eigen::Matrix3Xd& positions,
               const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars = {});

/// Writes a ParaView collection listing (time, file) pairs; files relative to the .pvd's directory. `notes`
/// (empty, or one per frame): an XML comment before each DataSet whose note is not empty.
void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& frames,
               const std::vector<std::string>& notes = {});

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
