#pragma once
// Running a built scene (the last of its three stages, scene.hpp): its Simulation stepped frame by frame by the
// driver (run/driver.hpp) into scene.output.dir — NNN.obj and NNN.vtu frames, frames.pvd, stats.json,
// stats.csv, checkpoint.bin, and a flesh run's own files (flesh_scene.hpp) — with a header and one line per
// frame in the log.
#include <ostream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/run/driver.hpp"
#include "snh/run/stats.hpp"
#include "snh/setup/scene_build.hpp"

namespace snh {

using FrameStats = StepRecord;

struct SceneResult : RunOutcome {
  std::vector<FrameStats> frames;  ///< frame 0 is the initial state
  CellType element = CellType::hex8;
  Eigen::Index vertices = 0, cells = 0;
  Eigen::VectorXd final_positions;
};

/// Runs a built scene (see the header). Stops at the first substep that fails (its frame and the stats are
/// still written). A starting state outside the energy's domain stops the run at frame 0 with that reason.
/// With scene.run.check_only, prints the header and the problem's size and runs nothing. Throws as
/// run_simulation (driver.hpp), SceneError when the scene has no output directory.
[[nodiscard]] SceneResult run_scene(const BuiltScene& built, std::ostream& log);
/// Builds the scene (build_scene), then runs it.
[[nodiscard]] SceneResult run_scene(const Scene& scene, std::ostream& log);

}  // namespace snh
