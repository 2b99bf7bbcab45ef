#include "snh/solve/newton.hpp"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace snh {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// The step rules: d (free DOFs) below step_tolerance, or below relative_step_tolerance of how far x has
/// moved from x0, or below the rounding of x's coordinates. `scale` multiplies every bound (the chord
/// step's test asks for the step rule's bound times kChordSteps).
bool step_is_small(const Eigen::VectorXd& d, const Eigen::VectorXd& x, const Eigen::VectorXd& x0, const NewtonOptions& o,
                   double scale = 1.0) {
  const double step = d.lpNorm<Eigen::Infinity>();
  if (o.step_tolerance > 0.0 && step < scale * o.step_tolerance) return true;
  if (!(o.relative_step_tolerance > 0.0)) return false;
  const double rounding = 64.0 * std::numeric_limits<double>::epsilon() * x.lpNorm<Eigen::Infinity>();
  return step <= scale * std::max(o.relative_step_tolerance * (x - x0).lpNorm<Eigen::Infinity>(), rounding);
}

/// The step rules end Newton only where ‖g‖ is within this factor of the tolerance (NewtonOptions).
constexpr double kStepRuleResidual = 10.0;

/// d below the rounding of x's coordinates: a step that cannot change x.
bool below_rounding(const Eigen::VectorXd& d, const Eigen::VectorXd& x) {
  return d.lpNorm<Eigen::Infinity>() <= 64.0 * std::numeric_limits<double>::epsilon() * x.lpNorm<Eigen::Infinity>();
}

/// An inexact solver's Newton iteration that follows a step within this many times the step rule's bound
/// solves with the matrix it already holds (a chord step) instead of assembling and preparing a new one.
/// 30: of 10, 30 and 100 on Figure 1, the fewest CG iterations with no more Newton iterations, and the
/// fastest steps (docs/results.md, "Newton"); 100 let poor chord steps cost extra Newton iterations.
constexpr double kChordSteps = 30.0;

/// The Newton direction d at x (gradient g) from a freshly assembled matrix: the true Hessian when it is
/// positive definite (a direct solver's Cholesky succeeds, or PCG meets no non-positive curvature) and gives
/// a descent direction, or when an inexact solver (mg, amg) met negative curvature late enough to return the
/// iterate before it (truncated Newton, LinearSolver::solve); otherwise the projected Hessian. CG stops at
/// a residual of `enough`, or of `projected_enough` on a projected Hessian that replaces a true one which
/// failed (another model than the one whose predictions set `enough`). `try_true` false goes straight to the
/// projected Hessian. Returns whether the true Hessian was tried and failed.
bool newton_direction(Problem& problem, const Eigen::VectorXd& x, const Eigen::VectorXd& g, HessianMatrix& H,
                      LinearSolver& solver, const NewtonOptions& options, bool try_true, double enough,
                      double projected_enough, NewtonReport& report, Eigen::VectorXd& d) {
  auto t = Clock::now();
  problem.hessian(x, H, try_true ? PsdProjection::none : options.projection);
  report.assembly_seconds += seconds_since(t);
  t = Clock::now();
  bool have_step = false;
  if (try_true && solver.try_factorize(H.matrix)) {
    d = solver.solve(-g, enough);
    report.linear_iterations += solver.last_iterations();
    have_step = d.allFinite() && g.dot(d) < 0.0;
    if (have_step) {
      ++report.true_hessian_steps;
      if (solver.last_truncated()) ++report.truncated_steps;
    }
  }
  if (!have_step) {
    if (try_true) {  // H held the true Hessian: assemble the projected one
      report.solve_seconds += seconds_since(t);
      t = Clock::now();
      problem.hessian(x, H, options.projection);
      report.assembly_seconds += seconds_since(t);
      t = Clock::now();
    }
    solver.factorize(H.matrix);
    d = solver.solve(-g, try_true ? projected_enough : enough);
    report.linear_iterations += solver.last_iterations();
  }
  report.solve_seconds += seconds_since(t);
  return try_true && !have_step;
}

/// A full step the line search accepted is doubled while the energy's slope along d at the accepted point is
/// still more than this fraction of its slope at x (the curvature condition of Wolfe's rules, c₂ = ½). An
/// exact Newton direction's slope vanishes at α = 1 wherever the Hessian is the energy's curvature; a slope
/// left at nearly its start says the matrix overestimated the curvature along d a great deal, as the
/// per-element PSD projection does where elements are compressed or turned inside out (an SNH element's twist
/// eigenvalues μ + λ(J − α)σ_k, 0 at rest, go negative as it is compressed): their negative curvature is
/// clamped away, and full steps of a hundredth of the way follow one another (docs/solvers.md, "Line search").
constexpr double kExpandSlope = 0.5;
/// At most this many doublings per line search (a step 2¹⁰ times the Newton step).
constexpr int kMaxExpansions = 10;

/// The iterate a backtracking line search accepted along d, with its energy and gradient.
struct LineSearch {
  bool accepted = false;
  double alpha = 0.0, energy = 0.0;
  Eigen::VectorXd x, gradient;
};

/// Doubles an accepted full step (ls at x + alpha d, alpha = 1) while kExpandSlope says so: each trial goes
/// from the accepted point as far again, bounded by the terms' max_step, and replaces it only where the energy is
/// finite and lower than there (and the Armijo rule from x holds); a trial that the terms cut short is the last.
void expand(Problem& problem, const Eigen::VectorXd& d, double E, double slope,
            const NewtonOptions& options, NewtonReport& report, double& alpha, LineSearch& ls) {
  Eigen::VectorXd trial, trial_gradient;
  for (int k = 0; k < kMaxExpansions && ls.gradient.dot(d) < kExpandSlope * slope; ++k) {
    // From the accepted point onward by alpha d, as far as the terms allow.
    const double bound = std::min(1.0, problem.max_step(ls.x, alpha * d));
    if (!(bound > 0.0)) return;
    trial = ls.x;
    problem.dofs().scatter_add_free(d, bound * alpha, trial);
    const double energy = problem.evaluate(trial, trial_gradient, nullptr, options.projection);
    const double next = alpha * (1.0 + bound);
    if (!std::isfinite(energy) || !(energy < ls.energy) || !(energy <= E + 1e-4 * next * slope)) return;
    ++report.line_search_expansions;
    alpha = next;
    ls.x.swap(trial);
    ls.gradient.swap(trial_gradient);
    ls.energy = energy;
    if (bound < 1.0) return;
  }
}

/// Backtracking (Armijo) from the largest step every term allows: x + α d for α halved until the energy falls
/// enough, or the full step where the energy is within rounding of E but the residual r falls. A full step
/// accepted at once is then doubled while the slope says the energy falls on steeply (kExpandSlope) and the
/// terms allow it. A failure (no step allowed, no decrease) is set in the report; its time, halvings and
/// doublings are counted there.
LineSearch line_search(Problem& problem, const Eigen::VectorXd& x, const Eigen::VectorXd& d, double E, double slope, double r,
                       const NewtonOptions& options, NewtonReport& report) {
  const auto t = Clock::now();
  LineSearch ls;
  double alpha = std::min(1.0, problem.max_step(x, d));
  if (!(alpha > 0.0)) {
    report.failure = fmt::format("no step is allowed at Newton iteration {} (the step bound is {:g})", report.iterations, alpha);
    report.assembly_seconds += seconds_since(t);
    return ls;
  }
  for (int h = 0; h <= options.max_halvings; ++h) {
    ls.x = x;
    problem.dofs().scatter_add_free(d, alpha, ls.x);
    ls.energy = problem.evaluate(ls.x, ls.gradient, nullptr, options.projection);  // the gradient for the next iterate
    if (std::isfinite(ls.energy) && ls.energy <= E + 1e-4 * alpha * slope) {
      ls.accepted = true;
      break;
    }
    // Within rounding of E: accept the full step if it reduces the residual.
    if (h == 0 && std::isfinite(ls.energy) && std::abs(ls.energy - E) <= 1e-12 * std::max(1.0, std::abs(E))) {
      if (ls.gradient.norm() < r) {
        ls.accepted = true;
        break;
      }
    }
    alpha *= 0.5;
    ++report.line_search_steps;
  }
  if (ls.accepted && alpha == 1.0) expand(problem, d, E, slope, options, report, alpha, ls);
  report.assembly_seconds += seconds_since(t);
  ls.alpha = alpha;
  if (!ls.accepted)
    report.failure = fmt::format("line search failed at Newton iteration {} (|g| = {:.3e}): no decrease of the energy "
                                 "along the Newton direction",
                                 report.iterations, r);
  return ls;
}

NewtonReport newton_iterations(Problem& problem, Eigen::VectorXd& x, LinearSolver& solver,
                               const NewtonOptions& options) {
  NewtonReport report;
  const Eigen::VectorXd x0 = options.relative_step_tolerance > 0.0 ? x : Eigen::VectorXd();
  Eigen::VectorXd g;
  HessianMatrix& H = problem.newton_matrix();
  // An iterative linear solve may stop at a residual that cannot decide convergence: a tenth of the tolerance.
  const double linear_enough = 0.1 * options.tolerance;
  // The energy and gradient come first (at the start, then from each accepted line-search trial); the
  // Hessian is assembled only once the iterate is known not to have converged (a solve that needs one
  // Newton step used to assemble two).
  auto t = Clock::now();
  double E = problem.evaluate(x, g, nullptr, options.projection);
  report.assembly_seconds += seconds_since(t);
  if (!std::isfinite(E)) {
    report.energy = E;
    report.residual = std::numeric_limits<double>::infinity();
    // +inf: an element with J <= 0 under an energy undefined there; NaN: an overflow, which the supported
    // ranges of parameters and coordinates (docs/cli.md, docs/scenes.md) keep out; saying J <= 0 for it misled.
    report.failure = std::isnan(E) ? "the energy is not a number at the starting state (an overflow: parameters or "
                                     "coordinates beyond the supported range)"
                                   : "the starting state is outside the energy's domain (an element has J <= 0)";
    return report;
  }
  double r0 = 0.0;
  // The last step taken was within kChordSteps of the step rule, and was not itself a chord step.
  bool chord_next = false;
  // The true Hessian failed at the last iteration: with skip_true_after_failure this one goes straight to the
  // projected Hessian (NewtonOptions), and the next tries the true one again.
  bool true_failed = false;
  // Eisenstat and Walker's first choice of forcing term: how far the last full step's linear model missed the
  // residual it reached, |‖g_k‖ − ‖g_{k−1} + H d_{k−1}‖| / ‖g_{k−1}‖ (the forcing's largest value where there is
  // no such step).
  double model_eta = options.forcing;
  for (;;) {
    const double r = g.norm();
    if (report.iterations == 0) r0 = r;
    report.residuals.push_back(r);
    report.residual = r;
    if (options.on_iteration) options.on_iteration(report.iterations, r);
    report.energy = E;
    if (r * r < options.tolerance * options.tolerance || r == 0.0) {
      report.converged = true;
      return report;
    }
    if (options.should_stop && options.should_stop()) {
      report.interrupted = true;
      report.failure = fmt::format("interrupted at Newton iteration {}", report.iterations);
      return report;
    }
    if (report.iterations >= options.max_iterations) {
      report.failure = fmt::format("no convergence in {} Newton iterations (|g| = {:.3e})", options.max_iterations, r);
      return report;
    }
    ++report.iterations;

    Eigen::VectorXd d;
    // Inexact Newton (Eisenstat and Walker's forcing terms): an iterative solver stops at a residual η‖g‖ with
    // η = min(forcing, √(‖g‖/‖g₀‖), model_eta). The rule √(‖g‖/‖g₀‖) is loose while ‖g‖ is far above its first
    // value and ever tighter as it falls, so that convergence stays superlinear. model_eta tightens the solve at
    // once where the last step's model predicted well (elasticity between two nearby frames is nearly
    // linear: one solve to the bound then does the work of several loose ones, and spares their assemblies) and
    // leaves the rule in charge where it did not (contact, inverted cells). The stopping rule is unchanged.
    const double rule_eta = solver.inexact() ? std::min(options.forcing, std::sqrt(r / r0)) : 0.0;
    const double eta = std::min(rule_eta, model_eta);
    const double enough = std::max(linear_enough, eta * r);
    // A chord step (an inexact solver, after a step within kChordSteps of the step rule): the matrix and
    // preconditioner of the last iteration serve again, sparing an assembly and a V-cycle set-up where a
    // Newton step is about to show convergence (on Figure 1 the last iteration of a step, far below the rule,
    // spent a good share of its time on them). Its step is tested and taken as any other; the next iteration
    // refreshes the matrix.
    bool have_step = false;
    if (chord_next) {
      t = Clock::now();
      d = solver.solve(-g, enough);
      report.linear_iterations += solver.last_iterations();
      report.solve_seconds += seconds_since(t);
      have_step = d.allFinite() && g.dot(d) < 0.0;
      if (have_step) ++report.chord_steps;
    }
    const bool chord = have_step;
    if (!have_step)
      true_failed = newton_direction(problem, x, g, H, solver, options,
                                     options.try_true_hessian && !(true_failed && options.skip_true_after_failure), enough,
                                     std::max(linear_enough, rule_eta * r), report, d);
    // Complete: solved afresh from this iterate's Hessian, neither truncated at negative curvature nor
    // replaced by steepest descent. Only such a direction's length says how far the answer is.
    bool complete = !chord && !solver.last_truncated();
    double slope = g.dot(d);
    bool d_from_solve = !solver.last_truncated();
    if (!d.allFinite() || !(slope < 0.0)) {  // not a descent direction: fall back to steepest descent
      d = -g;
      slope = -g.squaredNorm();
      complete = d_from_solve = false;
    }
    if (complete) report.last_step = d.lpNorm<Eigen::Infinity>();
    // The step rules end the solve only on a complete direction, and only where the force residual is
    // within kStepRuleResidual of the tolerance (or the step is below the coordinates' rounding, where ‖g‖
    // cannot fall further): a short step from a stiff Hessian says nothing about the forces left.
    if (complete && step_is_small(d, x, x0, options) &&
        (!(options.tolerance > 0.0) || r <= kStepRuleResidual * options.tolerance || below_rounding(d, x))) {
      report.converged = report.converged_by_step = true;
      return report;
    }

    // The linear residual ‖g + H d‖ the solve left (NaN where d is not a complete solve's: truncated, steepest
    // descent, or a direct solver's).
    const double linear_residual = d_from_solve ? solver.last_residual() : std::numeric_limits<double>::quiet_NaN();
    LineSearch ls = line_search(problem, x, d, E, slope, r, options, report);
    if (!ls.accepted) return report;
    chord_next = !chord && solver.inexact() && step_is_small(ls.alpha * d, x, x0, options, kChordSteps);
    // From a full step only: a shorter or a longer one says the model did not hold along d.
    model_eta = ls.alpha == 1.0 && std::isfinite(linear_residual) ? std::abs(ls.gradient.norm() - linear_residual) / r
                                                                  : options.forcing;
    x = std::move(ls.x);
    problem.on_accepted(x);
    E = ls.energy;
    g = std::move(ls.gradient);
  }
}

}  // namespace

NewtonReport newton_solve(Problem& problem, Eigen::VectorXd& x, LinearSolver& solver, const NewtonOptions& options) {
  const int factorizations = solver.factorizations();
  NewtonReport report = newton_iterations(problem, x, solver, options);
  report.factorizations = solver.factorizations() - factorizations;
  return report;
}

}  // namespace snh
