#pragma once
// The paper's stretch test (PAPER_CODE.md): a [−1, 1]³ box whose y = −1 and y = +1 vertex layers are
// pulled apart in equal quasi-static steps (y → ∓(1 + (stretch − 1) s/steps), x and z held), one
// Newton solve per step, an OBJ frame per step, and per-step statistics.
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "snh/material/lame.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/solve/linear_solver.hpp"
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
  bool reparametrize = false;             ///< params are linear μ_L, λ_L (MATH.md §2)
  int steps = 25;
  double stretch = 3.5;                   ///< final length / rest length along y
  std::filesystem::path out = "output";
  std::string solver = "cholmod";            ///< a linear_solvers() name
  bool reuse_factor = true;               ///< direct solvers: precondition with the last factor (linear_solver.hpp)
  NewtonOptions newton;
  std::string program = "snh stretch";    ///< for the header and stats.json
  std::string command_line;               ///< as the user typed it, for stats.json and the report
  bool write_vtu = true;                  ///< also NNN.vtu frames and frames.pvd for ParaView
  bool live_progress = false;             ///< log is a terminal: update the step's line at every Newton iteration
  /// Continue the run in `out` from its checkpoint (the last completed step); the settings must match.
  bool resume = false;
};

struct StepStats {
  int step = 0;
  bool converged = false;
  int newton_iterations = 0;
  int line_search_steps = 0;
  int linear_iterations = 0;  ///< conjugate-gradient iterations
  int factorizations = 0;     ///< numeric factorizations (direct solvers)
  int true_hessian_steps = 0;  ///< Newton iterations that used the unprojected Hessian
  double residual = 0.0;
  double energy = 0.0;
  double wall_seconds = 0.0;
  double assembly_seconds = 0.0;
  double solve_seconds = 0.0;
  double min_J = 0.0;         ///< smallest det F over all quadrature points
  int inverted = 0;           ///< elements with det F ≤ 0 somewhere
  double volume_ratio = 1.0;  ///< deformed / rest volume
  std::vector<double> residuals;
  std::string failure;
};

struct StretchResult {
  std::vector<StepStats> steps;
  bool all_converged = true;
  int interrupted_by = 0;     ///< the signal (SIGINT, SIGTERM) that stopped the run; 0 if none
  double total_seconds = 0.0;
  /// At the last step, the extent along the first other axis (x, or y when stretching along x) of the
  /// vertex layer nearest the middle (the largest rest coordinate along the axis not above the centre).
  double middle_width = 0.0;
  double peak_memory_mib = 0.0;  ///< peak resident memory of the process (VmHWM)
  double middle_rest_width = 0.0;  ///< the same extent at rest
  CellType element = CellType::tet4;
  Eigen::Index vertices = 0, cells = 0;
};

/// Checks the configuration (material, parameters, numbers, output directory) without running anything.
/// Throws std::invalid_argument, ParameterError, UnknownMaterial or WriteError with a one-line message.
void validate(const StretchConfig& config);

/// The settings that determine a run's result, as one line (for checkpoints).
[[nodiscard]] std::string fingerprint(const StretchConfig& config);

/// Runs the test, printing a header and one line per step to log, writing 000.obj … NNN.obj (and
/// NNN.vtu with frames.pvd), stats.json and stats.csv into config.out. Stops at the first step that fails to converge (its
/// frame and stats are still written).
[[nodiscard]] StretchResult run_stretch(const StretchConfig& config, std::ostream& log);

}  // namespace snh
