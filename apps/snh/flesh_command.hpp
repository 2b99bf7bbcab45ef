#pragma once
#include <CLI/CLI.hpp>

namespace snh::cli {

/// `snh flesh MODEL.glb [...]`: a rigged model's flesh driven by its bones.
void add_flesh_command(CLI::App& app, int& exit_code);

}  // namespace snh::cli
