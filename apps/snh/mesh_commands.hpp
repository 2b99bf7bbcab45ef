#pragma once
// `snh info MESH` and `snh convert IN OUT`: inspect and convert mesh files.
#include <CLI/CLI.hpp>

namespace snh::cli {

void add_mesh_commands(CLI::App& app, int& exit_code);

}  // namespace snh::cli
