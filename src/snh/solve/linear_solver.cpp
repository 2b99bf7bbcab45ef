#include "snh/solve/linear_solver.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/material/printable.hpp"
#include <fmt/ranges.h>

#include "snh/solve/direct_solver.hpp"
#include "snh/solve/multigrid.hpp"
#include "snh/solve/pcg_solver.hpp"

namespace snh {
namespace {

/// A direct solver, wrapped in factor reuse unless the options turn it off.
std::unique_ptr<LinearSolver> direct(std::unique_ptr<LinearSolver> solver, const LinearSolverOptions& o) {
  if (!o.reuse_factor) return solver;
  return with_factor_reuse(std::move(solver), o.tolerance, o.reuse_iterations);
}

/// "auto": the solver for this size and mesh (hexes are a lattice where mg can be made on them); a matrix
/// with no mesh behind it gets the direct solver.
std::unique_ptr<LinearSolver> automatic(const LinearSolverOptions& o, const SolverGeometry& g) {
  LinearSolverOptions chosen = o;
  Eigen::Index free = 0;
  if (g.free_index)
    for (int i : *g.free_index) free += i >= 0;
  if (!g.mesh || !g.free_index || auto_linear_solver(free, false) == "cholmod") {
    chosen.name = "cholmod";
    return make_linear_solver(chosen, g);
  }
  if (g.mesh->type == CellType::hex8) {
    try {
      chosen.name = "mg";
      return make_multigrid_solver(chosen, g);
    } catch (const std::invalid_argument&) {  // hexes that are not one lattice: amg
    }
  }
  chosen.name = "amg";
  return make_amg_solver(chosen, g);
}

}  // namespace

double search_diagonal_shift(const SparseLower& A, const std::function<bool(double)>& attempt) {
  Eigen::VectorXd row_abs = Eigen::VectorXd::Zero(A.rows());
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (SparseLower::InnerIterator it(A, c); it; ++it) {
      row_abs[it.row()] += std::abs(it.value());
      if (it.row() != it.col()) row_abs[it.col()] += std::abs(it.value());
    }
  const double bound = 4.0 * std::max(row_abs.size() ? row_abs.maxCoeff() : 0.0, 1e-300);
  const double first = 1e-10 * std::max(A.rows() ? A.diagonal().cwiseAbs().maxCoeff() : 0.0, 1e-300);
  for (double shift = first; std::isfinite(bound) && shift <= bound; shift *= 2.0)
    if (attempt(shift)) return shift;
  return std::numeric_limits<double>::quiet_NaN();
}

std::string_view auto_linear_solver(Eigen::Index free_dofs, bool hex_lattice) {
  if (free_dofs < kAutoIterativeFrom) return "cholmod";
  return hex_lattice ? "mg" : "amg";
}

const std::vector<LinearSolverInfo>& linear_solvers() {
  static const std::vector<LinearSolverInfo> registry = {
      {"cholmod", "CHOLMOD supernodal Cholesky (with factor reuse unless refactorizing)",
       [](const LinearSolverOptions& o, const SolverGeometry&) { return direct(make_cholmod_solver(), o); }},
      {"ldlt", "Eigen's simplicial LDLT (with factor reuse unless refactorizing)",
       [](const LinearSolverOptions& o, const SolverGeometry&) { return direct(make_ldlt_solver(), o); }},
      {"pcg", "conjugate gradients with a Jacobi preconditioner",
       [](const LinearSolverOptions& o, const SolverGeometry&) { return make_pcg_solver(o.tolerance); }},
      {"mg", "conjugate gradients with a geometric multigrid V-cycle (hexahedral lattices only)",
       [](const LinearSolverOptions& o, const SolverGeometry& g) { return make_multigrid_solver(o, g); }},
      {"amg", "conjugate gradients with an algebraic (smoothed-aggregation) multigrid V-cycle (any mesh)",
       [](const LinearSolverOptions& o, const SolverGeometry& g) { return make_amg_solver(o, g); }},
      {"auto", "by size: cholmod below 20 000 free DOFs, else mg on a hexahedral lattice and amg on any other mesh", automatic},
  };
  return registry;
}

std::vector<std::string> linear_solver_names() {
  std::vector<std::string> names;
  for (const auto& s : linear_solvers()) names.emplace_back(s.name);
  return names;
}

bool is_linear_solver(std::string_view name) {
  for (const auto& s : linear_solvers())
    if (s.name == name) return true;
  return false;
}

std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& o, const SolverGeometry& geometry) {
  if (!(o.tolerance > 0.0)) throw std::invalid_argument("linear solver tolerance must be > 0");
  if (o.reuse_iterations < 1) throw std::invalid_argument("reuse_iterations must be >= 1");
  for (const auto& s : linear_solvers())
    if (s.name == o.name) return s.make(o, geometry);
  throw std::invalid_argument(fmt::format("unknown linear solver '{}' (known: {})", printable(o.name),
                                          fmt::join(linear_solver_names(), ", ")));
}

}  // namespace snh
