#include "stretch_command.hpp"

#include <fmt/format.h>

#include <iostream>
#include <memory>

#include <unistd.h>
#include <omp.h>

#include "../common/command_line.hpp"
#include "../common/out_option.hpp"
#include "parameter_options.hpp"
#include "../common/run_report.hpp"
#include "snh/material/registry.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/setup/stretch.hpp"
#include "snh/solve/linear_solver.hpp"

namespace snh::cli {
namespace {

/// "Linear solver (default auto): NAME: what it is; ..." from the registry.
std::string linear_solver_help() {
  std::string out = "Linear solver (default auto)";
  for (const auto& s : linear_solvers()) out += fmt::format("; {}: {}", s.name, s.description);
  return out;
}

}  // namespace

namespace {

struct StretchOptions {
  std::string element = "tet";
  int res = 10;
  std::string material = "stable_neo_hookean";
  ParameterOptions params;
  int steps = 25;
  double stretch = 3.5;
  std::string out = "output";
  int threads = 0;
  std::string solver = "auto";
  double tolerance = 1e-3;
  std::string projection = "clamp";
  bool projected_only = false;
  bool refactorize = false;
  bool resume = false;
  bool no_report = false;
  bool force = false;
  std::string tet_split = "paper";
  std::string mesh, axis = "y";
};

}  // namespace

void add_stretch_command(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<StretchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "stretch",
      "The paper's stretch test (tetcli/hexcli) with named options: a [-1,1]^3 box of tets or hexes whose y = -1 and "
      "y = +1 layers are pulled apart in quasi-static steps; writes NNN.obj and NNN.vtu frames, frames.pvd, stats.json "
      "and stats.csv.");
  auto* element = cmd->add_option("--element", o->element, "tet (6 tets per lattice cell, as tetcli) or hex (trilinear, as hexcli)")
      ->check(CLI::IsMember({"tet", "hex"}));
  auto* res = cmd->add_option("--res", o->res, "Cells per side (default 10)");
  auto* mesh = cmd->add_option("--mesh", o->mesh,
                  "A mesh file (.node/.ele, .mesh, .msh, .vtu) instead of the box: its extreme vertex layers along --axis "
                  "are pulled apart");
  cmd->add_option("--axis", o->axis, "Stretch axis: x, y (default) or z")->check(CLI::IsMember({"x", "y", "z"}));
  auto* split = cmd->add_option("--tet-split", o->tet_split,
                  "paper (default: every cell cut around its c0-c7 diagonal, as tetcli) or mirrored (the cut mirrored "
                  "in the upper half of each axis, so that for even res the mesh is mirror symmetric)")
      ->check(CLI::IsMember({"paper", "mirrored"}));
  // They shape the generated box, which --mesh replaces: given together they were silently ignored.
  mesh->excludes(element)->excludes(res)->excludes(split);
  cmd->add_option("--material", o->material, "Energy (default stable_neo_hookean): " + material_name_list());
  add_parameter_options(cmd, o->params);
  cmd->add_option("--steps", o->steps, "Quasi-static steps (default 25)");
  cmd->add_option("--stretch", o->stretch, "Final length / rest length along y (default 3.5)");
  cmd->add_option("--out", o->out, "Output directory (default output)")->check(non_empty_path());
  cmd->add_option("--threads", o->threads, "OpenMP threads for assembly (default: all cores)")->check(CLI::Range(0, 1024));
  cmd->add_option("--solver", o->solver, linear_solver_help())->check(CLI::IsMember(linear_solver_names()));
  cmd->add_flag("--refactorize", o->refactorize,
                "Direct solvers: factorize every Newton matrix (by default the last factor preconditions conjugate "
                "gradients on the next matrix, and a new factorization is made only when that converges slowly)");
  cmd->add_flag("--resume", o->resume,
                "Continue a stopped run in --out from its last completed step (the other options must be the same)");
  cmd->add_flag("--force", o->force, "Write into --out even if it is not empty and holds no snh run (files with the names of ours are replaced)");
  cmd->add_flag("--no-report", o->no_report, "Do not write the browser report (index.html; snh report DIR writes it later)");
  cmd->add_option("--tolerance", o->tolerance, "Newton stops when |f| < tolerance (default 1e-3: |f|^2 < 1e-6 as the paper)");
  cmd->add_option("--projection", o->projection, "PSD projection of element Hessians: clamp (default) or abs")
      ->check(CLI::IsMember({"clamp", "abs"}));
  cmd->add_flag("--projected-only", o->projected_only,
                "Always use the projected Hessian (by default a direct solver first tries the true one, for quadratic "
                "convergence near the solution)");
  cmd->callback([o, &exit_code]() {
    StretchConfig c;
    c.program = "snh stretch";
    c.command_line = invocation();
    c.element = o->element == "hex" ? CellType::hex8 : CellType::tet4;
    c.resolution = o->res;
    c.mesh_file = o->mesh;
    c.axis = o->axis[0] - 'x';
    c.tet_split = o->tet_split == "mirrored" ? TetSplit::mirrored : TetSplit::paper;
    c.material = o->material;
    c.params = o->params.lame();
    c.reparametrize = o->params.reparametrize;
    c.steps = o->steps;
    c.stretch = o->stretch;
    c.out = o->out;
    c.solver = o->solver;
    c.reuse_factor = !o->refactorize;
    c.resume = o->resume;
    c.newton.tolerance = o->tolerance;
    c.newton.projection = *parse_projection(o->projection);
    c.newton.try_true_hessian = !o->projected_only;
    if (o->threads > 0) omp_set_num_threads(o->threads);
    c.live_progress = ::isatty(STDOUT_FILENO) != 0;
    validate(c);
    install_stop_handlers();
    // The directory stays locked until the report is written: no other run can start there meanwhile.
    c.lock = std::make_shared<RunDirectoryLock>(c.out, o->force);
    const StretchResult r = run_stretch(c, std::cout);
    if (!o->no_report) (void)write_run_report(c.out, "snh");
    exit_code = r.interrupted_by ? 128 + r.interrupted_by : r.all_converged ? 0 : 1;
  });
}

}  // namespace snh::cli
