#include "lab_command.hpp"

#include <iostream>
#include <memory>

#include <unistd.h>

#include "../common/command_line.hpp"
#include "../common/out_option.hpp"
#include "../common/run_report.hpp"
#include "parameter_options.hpp"
#include "snh/material/registry.hpp"
#include "snh/setup/lab.hpp"
#include "snh/run/run_directory.hpp"

namespace snh::cli {

void add_lab_command(CLI::App& app, int& exit_code) {
  struct Options {
    bool quick = false, json = false, no_report = false, force = false;
    std::string out = "output/lab";
    std::vector<std::string> energies;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "lab",
      "The stability lab: simulations that show the paper's claims for every energy side by side (rest, inversion, "
      "reflection, recovery from degeneracy, Poisson's ratio, volume under large stretch). Prints the tables and "
      "writes lab.json and every run's frames and stats under --out.");
  cmd->add_flag("--quick", o->quick, "Smaller meshes and shorter times (about 4x faster)");
  cmd->add_flag("--json", o->json, "Print lab.json to stdout instead of the tables");
  cmd->add_option("--out", o->out, "Output directory (default output/lab)")->check(non_empty_path());
  cmd->add_flag("--force", o->force, "Write into --out even if it is not empty and holds no snh run (files with the names of ours are replaced)");
  cmd->add_flag("--no-report", o->no_report,
                "Do not write the browser reports (OUT/index.html and one per simulation; snh report OUT writes them later)");
  cmd->add_option("--energy", o->energies, "Only these energies (repeatable; default all): " + material_name_list())
      ->check(CLI::IsMember(std::vector<std::string>(material_names().begin(), material_names().end())));
  cmd->callback([o, &exit_code]() {
    LabOptions lo;
    lo.quick = o->quick;
    lo.out = o->out;
    lo.energies = o->energies;
    lo.command_line = invocation();
    lo.progress = o->json ? nullptr : &std::cerr;
    // Locked (and refused if it holds someone else's files) until the reports are written.
    const RunDirectoryLock lock(o->out, o->force);
    const LabReport r = run_lab(lo);
    if (o->json) std::cout << r.json.dump(1) << "\n";
    else std::cout << r.text << "\nlab.json and every run's frames and stats: " << o->out << "\n";
    if (!o->no_report) {
      if (o->json) {  // stdout holds the JSON alone
        std::streambuf* saved = std::cout.rdbuf(std::cerr.rdbuf());
        (void)write_run_report(o->out, "snh");
        std::cout.rdbuf(saved);
      } else {
        (void)write_run_report(o->out, "snh");
      }
    }
    exit_code = 0;
  });
}

}  // namespace snh::cli
