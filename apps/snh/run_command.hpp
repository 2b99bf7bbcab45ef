#pragma once
// `snh run SCENE.json`: runs a scene file (dynamics or quasi-static, pins, initial deformation).
#include <CLI/CLI.hpp>

#include "snh/setup/scene_build.hpp"

namespace snh::cli {

void add_run_command(CLI::App& app, int& exit_code);

/// Runs a built scene from the command line (snh run, snh flesh): its command line and live progress set,
/// Ctrl-C handled, the output directory locked until the report (unless `no_report`) is written. `force`: write
/// into an output directory that is not empty and holds no run of ours (refused otherwise). Returns the exit
/// code: 0 when every frame converged, 1 when the run stopped early, 128 + the signal.
[[nodiscard]] int run_scene_command(BuiltScene& built, bool no_report, bool force);

}  // namespace snh::cli
