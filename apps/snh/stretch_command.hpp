#pragma once
// `snh stretch`: the paper's stretch test with named options, any material and element type.
#include <CLI/CLI.hpp>

namespace snh::cli {

void add_stretch_command(CLI::App& app, int& exit_code);

}  // namespace snh::cli
