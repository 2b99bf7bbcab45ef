// snh: command-line entry point. Subcommands live in one file each.
#include <exception>
#include <iostream>
#include <string>

#include <CLI/CLI.hpp>

#include "../common/command_line.hpp"
#include "../common/process_env.hpp"
#include "../common/out_option.hpp"
#include "flesh_command.hpp"
#include "lab_command.hpp"
#include "material_command.hpp"
#include "mesh_commands.hpp"
#include "report_commands.hpp"
#include "run_command.hpp"
#include "snh/math/keep_memory.hpp"
#include "snh/solve/memory_estimate.hpp"
#include "stretch_command.hpp"
#include "snh/io/atomic_file.hpp"

namespace {
/// `snh run` takes its solver from the scene file: a memory message's "--solver pcg" names the scene's field.
std::string pcg_option_for(const CLI::App& app, std::string message) {
  if (!app.got_subcommand("run")) return message;
  const std::string option = "--solver pcg", field = "the scene's \"solver\": {\"linear\": \"pcg\"}";
  for (auto at = message.find(option); at != std::string::npos; at = message.find(option, at + field.size()))
    message.replace(at, option.size(), field);
  return message;
}
}  // namespace

int main(int argc, char** argv) {
  snh::cli::ensure_process_settings(argv);
  snh::keep_freed_memory();
  snh::cli::invocation() = snh::cli::quoted_command_line(argc, argv);
  CLI::App app{"snh " SNH_VERSION ": Stable Neo-Hookean flesh simulation toolkit (Smith, de Goes & Kim 2018)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "snh " SNH_VERSION);
  // Usage errors: one line and exit code 2, like every other bad input.
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("snh: error: ") + e.what() + " (see snh --help)\n";
  });
  int exit_code = 0;
  snh::cli::add_material_command(app, exit_code);
  snh::cli::add_stretch_command(app, exit_code);
  snh::cli::add_run_command(app, exit_code);
  snh::cli::add_flesh_command(app, exit_code);
  snh::cli::add_lab_command(app, exit_code);
  snh::cli::add_mesh_commands(app, exit_code);
  snh::cli::add_report_commands(app, exit_code);
  snh::cli::refuse_non_finite_numbers(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help and --version succeed
  } catch (const snh::WriteError& e) {  // a file that could not be written (disk full, no permission): 3
    std::cerr << "snh: error: " << e.what() << "\n";
    return 3;
  } catch (const snh::MemoryEstimateError& e) {  // refused before any work
    std::cerr << "snh: error: " << pcg_option_for(app, e.what()) << "\n";
    return 2;
  } catch (const snh::OutOfMemoryError& e) {  // a run out of memory: one line, exit 1 (frames kept)
    std::cerr << "snh: error: " << pcg_option_for(app, e.what()) << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "snh: error: out of memory (an allocation failed; docs/solvers.md, \"Memory\", says what a run needs)\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "snh: error: " << e.what() << "\n";
    return 2;
  }
  return exit_code;
}
