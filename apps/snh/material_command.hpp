#pragma once
// `snh material`: inspect one energy at one F, list the energies, or measure the stability table.
#include <CLI/CLI.hpp>

namespace snh::cli {

/// Registers the `material` subcommand on app; its callback runs the command and sets exit_code.
void add_material_command(CLI::App& app, int& exit_code);

}  // namespace snh::cli
