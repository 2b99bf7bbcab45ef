#pragma once
// What every run writes (DESIGN.md sim/): frames as NNN.obj (the paper's format: lattice vertices and
// the boundary triangles) and NNN.vtu with a frames.pvd series for ParaView, each file written
// atomically; and the process' peak memory for the stats.
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/elastic_term.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Peak resident memory of this process in MiB (VmHWM from /proc/self/status; 0 where unavailable).
[[nodiscard]] double peak_memory_mib();

/// "; worst element E (min det F = J)": the cell with the smallest det F over its quadrature points, for
/// a failure diagnostic ("" for no cells).
[[nodiscard]] std::string worst_element(const Eigen::VectorXd& min_J);

class FrameWriter {
 public:
  /// mesh: the rest mesh (copied); write_vtu: also NNN.vtu frames and frames.pvd; pinned: #V flags of
  /// the vertices held or moved by the boundary conditions (written as the point field "pinned").
  FrameWriter(std::filesystem::path out, const VolumeMesh& mesh, bool write_vtu, const std::vector<bool>& pinned);
  /// Writes frame `index` at `time`: NNN.obj, and NNN.vtu (point fields displacement and pinned; cell
  /// fields J, the min det F, and psi, the mean energy density) with the .pvd series rewritten to include it.
  ///   x  deformed positions, 3 #V
  ///   d  the deformation at x (ElasticTerm::deformation)
  void write(int index, double time, const Eigen::VectorXd& x, const ElasticTerm::Deformation& d);
  /// Continues a series whose frames 0 … last are already on disk (a resumed run): lists them in the
  /// .pvd at time(i) without writing anything.
  void adopt_written(int last, const std::function<double(int)>& time);
  [[nodiscard]] const Eigen::Matrix3Xi& surface() const { return surface_; }

 private:
  std::filesystem::path out_;
  VolumeMesh mesh_;
  Eigen::Matrix3Xi surface_;
  bool write_vtu_;
  Eigen::VectorXd pinned_;
  std::vector<std::pair<double, std::string>> series_;
};

}  // namespace snh
