#pragma once
// What every run writes (docs/design.md): frames as NNN.obj (the paper's format: lattice vertices and
// the boundary triangles) and NNN.vtu (binary) with a frames.pvd series for ParaView, each file written
// atomically; and the process' peak memory for the stats.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/elastic_term.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Peak resident memory of this process in MiB (VmHWM from /proc/self/status; 0 where unavailable).
[[nodiscard]] double peak_memory_mib();

class FrameWriter {
 public:
  /// mesh: the rest mesh; write_vtu: also NNN.vtu frames and frames.pvd; pinned: #V flags of the
  /// vertices held or moved by the boundary conditions (written as the point field "pinned"). What every
  /// frame shares (the surface's face lines, the .vtu cell arrays) is made here, once.
  FrameWriter(std::filesystem::path out, const VolumeMesh& mesh, bool write_vtu, const std::vector<bool>& pinned);
  /// Writes frame `index` at `time`: NNN.obj, and NNN.vtu (point fields displacement and pinned; cell
  /// fields J, the min det F, and psi, the mean energy density), and adds it to the series that
  /// write_series writes.
  ///   x  deformed positions, 3 #V
  ///   d  the deformation at x (ElasticTerm::deformation)
  void write(int index, double time, const Eigen::VectorXd& x, const ElasticTerm::Deformation& d);
  /// Writes frames.pvd listing every frame written or adopted so far (nothing without .vtu frames).
  void write_series() const;
  /// Continues a series whose frames 0 … last are already on disk (a resumed run): lists them in the
  /// series at time(i) without writing anything.
  void adopt_written(int last, const std::function<double(int)>& time);
  [[nodiscard]] const Eigen::Matrix3Xi& surface() const { return surface_; }

 private:
  std::filesystem::path out_;
  Eigen::Matrix3Xd rest_;
  Eigen::Matrix3Xi surface_;
  std::string faces_;  // the surface's `f a b c` lines of every NNN.obj
  std::optional<VtuWriter> vtu_;
  Eigen::VectorXd pinned_;
  std::vector<std::pair<double, std::string>> series_;
};

}  // namespace snh
