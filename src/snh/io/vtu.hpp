#pragma once
// VTK XML unstructured grids (.vtu, ASCII) and ParaView series (.pvd) for frames of a volume mesh.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

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

}  // namespace snh
