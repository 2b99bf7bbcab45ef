// tetcli / tetccli / hexcli: the paper's stretch-test programs, same positional arguments
// (docs/paper-programs.md):  tetcli resolution material_model mu lambda [output_directory]
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <string>

#include <fmt/format.h>
#include <unistd.h>

#include "../common/command_line.hpp"
#include "../common/process_env.hpp"
#include "../common/run_report.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/math/keep_memory.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/run/run_directory.hpp"
#include "snh/setup/stretch.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace {

constexpr bool kHex = SNH_HEX;

[[noreturn]] void fail(const std::string& program, const std::string& message) {
  std::cerr << program << ": error: " << message << "\n";
  std::exit(2);
}

int parse_int(const std::string& program, const char* what, const char* text) {
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || errno != 0 || v < 1 || v > 400)
    fail(program, fmt::format("{} must be an integer from 1 to 400, got '{}'", what, text));
  return static_cast<int>(v);
}

double parse_double(const std::string& program, const char* what, const char* text) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || errno != 0 || !std::isfinite(v))
    fail(program, fmt::format("{} must be a finite number, got '{}'", what, text));
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  snh::cli::ensure_process_settings(argv);
  snh::keep_freed_memory();
  std::string program = argv[0];
  if (const auto slash = program.find_last_of('/'); slash != std::string::npos) program = program.substr(slash + 1);
  const std::string usage = fmt::format(
      "usage: {} resolution material_model mu lambda [output_directory]\n"
      "  The paper's stretch test on a [-1,1]^3 {} lattice with resolution^3 cells: the y = -1 and y = +1 layers\n"
      "  move apart in 25 quasi-static steps to a 3.5x stretch; frames 000.obj .. 025.obj (and .vtu), stats.json,\n"
      "  stats.csv and index.html (the browser report) go to output_directory (default: output). mu and lambda\n"
      "  are used as given.\n"
      "  example: {} 10 stable_neo_hookean 1.0 10.0 output\n",
      program, kHex ? "hexahedral (trilinear, 2x2x2 Gauss points)" : "tetrahedral (6 tets per cell)", program);
  if (argc == 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::cout << usage;
    return 0;
  }
  if (argc < 5 || argc > 6) {
    std::cerr << program << ": error: expected 4 or 5 arguments, got " << argc - 1 << "\n" << usage;
    return 2;
  }
  snh::StretchConfig config;
  config.program = program;
  config.solver = "pcg";  // the paper's programs solved with Jacobi-preconditioned CG (docs/paper-programs.md); snh stretch chooses by size
  config.command_line = snh::cli::quoted_command_line(argc, argv);
  config.element = kHex ? snh::CellType::hex8 : snh::CellType::tet4;
  config.resolution = parse_int(program, "resolution", argv[1]);
  config.material = argv[2];
  config.params = {parse_double(program, "mu", argv[3]), parse_double(program, "lambda", argv[4])};
  config.out = argc == 6 ? argv[5] : "output";
  if (config.out.empty()) fail(program, "output_directory is empty: give a directory (or leave it out for output)");
  try {
    config.live_progress = ::isatty(STDOUT_FILENO) != 0;
    snh::validate(config);
    snh::install_stop_handlers();
    // The directory stays locked until the report is written: no other run can start there meanwhile.
    snh::refuse_foreign_directory(config.out, "choose an empty or new output directory");
    config.lock = std::make_shared<snh::RunDirectoryLock>(config.out);
    const snh::StretchResult result = snh::run_stretch(config, std::cout);
    (void)snh::cli::write_run_report(config.out, program);  // the browser report; a failure keeps the results
    if (result.interrupted_by) return 128 + result.interrupted_by;
    return result.all_converged ? 0 : 1;
  } catch (const snh::WriteError& e) {  // a file that could not be written (disk full, no permission): 3
    std::cerr << program << ": error: " << e.what() << "\n";
    return 3;
  } catch (const snh::OutOfMemoryError& e) {  // one line, exit 1; the completed steps are kept
    std::cerr << program << ": error: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << program << ": error: "
              << snh::out_of_memory_message("the run", snh::lattice_size(config.resolution, config.element), config.solver)
              << "\n";
    return 1;
  } catch (const snh::MemoryEstimateError& e) {  // refused before any work: exit 2
    fail(program, e.what());
  } catch (const std::exception& e) {
    fail(program, e.what());
  }
}
