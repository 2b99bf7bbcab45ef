#pragma once
// `snh report DIR` (writes a run's browser report) and `snh render DIR` (a frame as a PNG through
// headless Chromium).
#include <CLI/CLI.hpp>

namespace snh::cli {

void add_report_commands(CLI::App& app, int& exit_code);

}  // namespace snh::cli
