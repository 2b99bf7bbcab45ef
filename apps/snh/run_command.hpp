#pragma once
// `snh run SCENE.json`: runs a scene file (dynamics or quasi-static, pins, initial deformation).
#include <CLI/CLI.hpp>

namespace snh::cli {

void add_run_command(CLI::App& app, int& exit_code);

}  // namespace snh::cli
