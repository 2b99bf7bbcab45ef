#pragma once
// What every run writes (docs/design.md): frames as NNN.obj (the paper's format: lattice vertices and
// the boundary triangles) and NNN.vtu (binary) with a frames.pvd series for ParaView, each file written
// atomically; and the process' peak memory for the stats.
#include <filesystem>
#include <functional>
#include <initializer_list>
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

/// The name prefix of the files of a frame where a run stopped without converging: failed_NNN.obj.
inline constexpr const char* kFailedPrefix = "failed_";

/// Removes failed_NNN files of frame `index` in `dir`, one per extension (".obj"), left by a run that stopped
/// there: a resumed run that gets past the frame writes it as NNN.
void remove_failed_frame(const std::filesystem::path& dir, int index, std::initializer_list<const char*> extensions);

class FrameWriter {
 public:
  /// mesh: the rest mesh; write_vtu: also NNN.vtu frames and frames.pvd; pinned: #V flags of the
  /// vertices held or moved by the boundary conditions (written as the point field "pinned"). What every
  /// frame shares (the surface's face lines, the .vtu cell arrays) is made here, once.
  FrameWriter(std::filesystem::path out, const VolumeMesh& mesh, bool write_vtu, const std::vector<bool>& pinned);
  /// Writes frame `index` at `time`: NNN.obj, and NNN.vtu (point fields displacement and pinned; cell
  /// fields J, the min det F, psi, the mean energy density, and for a mesh with muscle cells contraction,
  /// each cell's active strain α), and adds it to the series that
  /// write_series writes, with `note` (a frame that did not converge says so there) where not empty.
  /// A frame of `kFailedPrefix`: failed_NNN.obj and .vtu, outside the series (the state where a run
  /// stopped, not a result). A frame written in the series removes a failed one of its index.
  ///   x  deformed positions, 3 #V
  ///   d  the deformation at x (ElasticTerm::deformation)
  void write(int index, double time, const Eigen::VectorXd& x, const ElasticTerm::Deformation& d,
             const std::string& prefix = "", const std::string& note = "");
  /// Writes frames.pvd listing every frame written or adopted so far (nothing without .vtu frames).
  void write_series() const;
  /// Continues a series whose frames 0 … last are already on disk (a resumed run): lists them in the
  /// series at time(i), with note(i), without writing anything.
  void adopt_written(int last, const std::function<double(int)>& time, const std::function<std::string(int)>& note);
  [[nodiscard]] const Eigen::Matrix3Xi& surface() const { return surface_; }

 private:
  std::filesystem::path out_;
  Eigen::Matrix3Xd rest_;
  Eigen::Matrix3Xi surface_;
  std::string faces_;  // the surface's `f a b c` lines of every NNN.obj
  std::optional<VtuWriter> vtu_;
  Eigen::VectorXd pinned_;
  std::vector<std::pair<double, std::string>> series_;
  std::vector<std::string> notes_;  // one per series_ entry
};

}  // namespace snh
