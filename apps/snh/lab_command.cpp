#include "lab_command.hpp"

#include <iostream>
#include <memory>

#include <unistd.h>

#include "parameter_options.hpp"
#include "snh/material/registry.hpp"
#include "snh/sim/lab.hpp"

namespace snh::cli {

void add_lab_command(CLI::App& app, int& exit_code) {
  struct Options {
    bool quick = false, json = false;
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
  cmd->add_option("--out", o->out, "Output directory (default output/lab)");
  cmd->add_option("--energy", o->energies, "Only these energies (repeatable; default all): " + material_name_list())
      ->check(CLI::IsMember(std::vector<std::string>(material_names().begin(), material_names().end())));
  cmd->callback([o, &exit_code]() {
    LabOptions lo;
    lo.quick = o->quick;
    lo.out = o->out;
    lo.energies = o->energies;
    lo.progress = o->json ? nullptr : &std::cerr;
    const LabReport r = run_lab(lo);
    if (o->json) std::cout << r.json.dump(1) << "\n";
    else std::cout << r.text << "\nlab.json and every run's frames and stats: " << o->out << "\n";
    exit_code = 0;
  });
}

}  // namespace snh::cli
