#pragma once
// `snh lab`: the stability lab, every experiment for every energy, as tables or JSON.
#include <CLI/CLI.hpp>

namespace snh::cli {

void add_lab_command(CLI::App& app, int& exit_code);

}  // namespace snh::cli
