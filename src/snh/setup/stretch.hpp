#pragma once
// The paper's stretch test (docs/paper-programs.md): a [−1, 1]³ box whose y = −1 and y = +1 vertex layers are
// pulled apart in equal quasi-static steps (y → ∓(1 + (stretch − 1) s/steps), x and z held), one
// Newton solve per step, an OBJ frame per step, and per-step statistics.
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "snh/material/lame.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/run/driver.hpp"
#include "snh/run/run_directory.hpp"
#include "snh/run/stats.hpp"
#include "snh/solve/newton.hpp"

namespace snh {

struct StretchConfig {
  CellType element = CellType::tet4;
  int resolution = 10;                    ///< cells per side
  TetSplit tet_split = TetSplit::paper;   ///< how tets cut the lattice cells (box.hpp)
  /// A mesh file instead of the box (io/mesh_read.hpp); element, resolution and tet_split then unused.
  std::filesystem::path mesh_file;
  int axis = 1;                           ///< the stretch axis (0 x, 1 y, 2 z): its extreme faces are pulled
  std::string material = "stable_neo_hookean";
  Lame params{1.0, 10.0};
  bool reparametrize = false;             ///< params are linear μ_L, λ_L (docs/math.md §2)
  int steps = 25;
  double stretch = 3.5;                   ///< final length / rest length along y
  std::filesystem::path out = "output";
  std::string solver = "auto";               ///< a linear_solvers() name ("auto": by size)
  bool reuse_factor = true;               ///< direct solvers: precondition with the last factor (linear_solver.hpp)
  /// Inexact Newton's forcing 0.01 (NewtonOptions::forcing): here a Newton iteration costs more than a CG
  /// one, and the tighter forcing takes fewer Newton iterations (docs/results.md).
  NewtonOptions newton = [] {
    NewtonOptions o;
    o.forcing = 0.01;
    return o;
  }();
  std::string program = "snh stretch";    ///< for the header and stats.json
  std::string command_line;               ///< as the user typed it, for stats.json and the report
  bool write_vtu = true;                  ///< also NNN.vtu frames and frames.pvd for ParaView
  double progress_interval = 1.0;         ///< seconds between writes of the stats and checkpoint (RunPlan)
  bool live_progress = false;             ///< log is a terminal: update the step's line at every Newton iteration
  /// Continue the run in `out` from its checkpoint (the last completed step); the settings must match.
  bool resume = false;
  /// The lock on `out` if the caller holds it (run_directory.hpp); null: the run takes it for itself.
  std::shared_ptr<RunDirectoryLock> lock;
};

using StepStats = StepRecord;

/// The stretch test's kinematic layers: the vertices' rest positions with their coordinate along the axis
/// scaled about the centre by 1 + (stretch − 1) t / steps at time t (the step number).
class AxisStretch final : public KinematicProvider {
 public:
  ///   rest     3 by n, the layers' rest positions
  AxisStretch(Eigen::Matrix3Xd rest, int axis, double centre, double stretch, int steps)
      : rest_(std::move(rest)), axis_(axis), centre_(centre), stretch_(stretch), steps_(steps) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override;
  /// Length at time t relative to the rest length.
  [[nodiscard]] double length(double t) const { return 1.0 + (stretch_ - 1.0) * t / steps_; }

 private:
  Eigen::Matrix3Xd rest_;
  int axis_;
  double centre_, stretch_;
  int steps_;
};

struct StretchResult : RunOutcome {
  std::vector<StepStats> steps;
  /// At the last step, the extent along the first other axis (x, or y when stretching along x) of the
  /// vertex layer nearest the middle (the largest rest coordinate along the axis not above the centre);
  /// NaN (stats.json null, "n/a") when that layer is one vertex wide or is the pinned end layer.
  double middle_width = 0.0;
  double middle_rest_width = 0.0;  ///< the same extent at rest
  CellType element = CellType::tet4;
  Eigen::Index vertices = 0, cells = 0;
};

/// Checks the configuration (material, parameters, numbers, output directory) without running anything.
/// Throws std::invalid_argument, ParameterError, UnknownMaterial or WriteError with a one-line message.
void validate(const StretchConfig& config);

/// The settings that determine a run's result, as one line (for checkpoints); a mesh file by its contents.
[[nodiscard]] std::string fingerprint(const StretchConfig& config);

/// Runs the test (a Simulation of the layers' AxisStretch, run by the driver), printing a header and one
/// line per step to log, writing 000.obj … NNN.obj (and NNN.vtu with frames.pvd), stats.json, stats.csv
/// and checkpoint.bin into config.out. Stops at the first step that fails to converge (its frame and
/// stats are still written).
[[nodiscard]] StretchResult run_stretch(const StretchConfig& config, std::ostream& log);

}  // namespace snh
