#include "snh/setup/scene/sections.hpp"
#include "snh/solve/linear_solver.hpp"

namespace snh::scene {

SolverSpec parse_solver(Keys& top) {
  SolverSpec s;
  if (const json* solver = top.get("solver")) {
    Keys k(*solver, "solver", top.file());
    s.linear = k.choice("linear", s.linear, linear_solver_names());
    s.refactorize = k.boolean("refactorize", s.refactorize);
    // Given, an absolute tolerance on |g| replaces the fraction of E l² (a flesh scene's: of E h²).
    if (k.has("tolerance")) s.tolerance = k.positive("tolerance", 0.0);
    if (const double step = k.non_negative("step_tolerance", 0.0); k.has("step_tolerance")) s.step_tolerance = step;
    s.newton.relative_step_tolerance = k.non_negative("relative_step_tolerance", s.newton.relative_step_tolerance);
    s.newton.max_iterations = static_cast<int>(k.integer("max_iterations", s.newton.max_iterations, 1, 100000));
    if (k.has("max_iterations")) s.max_iterations = s.newton.max_iterations;
    s.newton.try_true_hessian = !k.boolean("projected_only", !s.newton.try_true_hessian);
    s.step_halvings = static_cast<int>(k.integer("step_halvings", s.step_halvings, 0, 20));
    k.finish();
  }
  return s;
}

OutputSpec parse_output(Keys& top, const std::filesystem::path& source) {
  OutputSpec s;
  if (const json* output = top.get("output")) {
    Keys k(*output, "output", top.file());
    if (const json* dir = k.get("dir")) {
      if (!dir->is_string() || dir->get<std::string>().empty()) k.fail("expected a directory name", "dir");
      s.dir = dir->get<std::string>();
    }
    s.vtu = k.boolean("vtu", s.vtu);
    k.finish();
  }
  if (s.dir.empty()) s.dir = std::filesystem::path("output") / source.stem();
  return s;
}

}  // namespace snh::scene
