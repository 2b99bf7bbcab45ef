#pragma once
// Projected Newton on the free DOFs with a backtracking (Armijo) line search on the total energy.
//
// Stopping rule: converged when ‖g‖² < tolerance² on the free DOFs (g = ∂E/∂x, the negative of the
// elastic forces): with the default tolerance 1e-3 this is the paper programs' ‖f‖² < 1e-6, absolute.
// Each iteration uses the true Hessian when the linear solver finds it positive definite (so Newton
// converges quadratically near a stable equilibrium, where element-wise projection would make it
// linear), and otherwise the Hessian assembled from PSD-projected element Hessians, which always
// gives a descent direction; the iteration after one whose true Hessian failed goes straight to the
// projected Hessian. It steps along d = −H⁻¹g and halves the step
// until E(x + αd) ≤ E(x) + 1e-4 α gᵀd. A state where the energy is undefined (+∞) counts as a failed
// trial, so the step gets shorter; no NaN enters x. The line search starts at α₀ = min(1, the problem's
// step bound) (a term's max_step: continuous collision detection for contact), and every accepted
// iterate is passed to the problem's on_accepted. Near convergence, where the energy decrease is below
// its rounding error, a full step that reduces ‖g‖ is accepted. A full step accepted at once is doubled
// while the slope gᵀd at the new point stays above half its start and the energy falls (the projected
// Hessian overestimates the curvature where elements are compressed or inverted: full steps then come out
// short). Iterative linear solves may stop once
// ‖Hd + g‖ is below a tenth of the tolerance, which cannot decide convergence. Optionally (step_tolerance
// > 0) Newton also stops when the Newton step's largest entry is below step_tolerance (the criterion of
// IPC and PolyFEM: scale-aware where an absolute ‖g‖ is not), or (relative_step_tolerance > 0) below
// that fraction of how far the solve has moved x, or below the coordinates' rounding. A step rule stops
// before taking that last step, and only on a complete direction (solved afresh from the iterate's Hessian:
// not a chord step, not truncated at negative curvature, not the steepest-descent fallback) and where ‖g‖
// is within 10 times the tolerance (or the step is below the rounding, where ‖g‖ cannot fall further);
// otherwise the step is taken and Newton goes on. So a solve that says `converged` has ‖g‖ below 10 times
// the tolerance, or could not lower it in this arithmetic (docs/solvers.md, "When a solve has converged"). Each line-search trial evaluates the energy and the gradient, so the
// accepted trial's serve the next iteration; the Hessian is assembled only once the convergence test has
// failed (one per Newton step; none for a converged start).
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/problem.hpp"
#include "snh/solve/linear_solver.hpp"

namespace snh {

struct NewtonOptions {
  int max_iterations = 50;        ///< the paper programs' limit
  double tolerance = 1e-3;        ///< on ‖g‖ (free DOFs)
  double step_tolerance = 0.0;    ///< > 0: also converged when ‖d‖∞ of the Newton step d is below this
  /// > 0: also converged when ‖d‖∞ ≤ this · ‖x − x₀‖∞ (x₀ the starting iterate: relative to what Newton has
  /// moved), or when d is below the rounding of the coordinates (64 ε ‖x‖∞): a step rule in units of the
  /// solve's own motion, for any length or time scale.
  double relative_step_tolerance = 0.0;
  PsdProjection projection = PsdProjection::clamp;
  bool try_true_hessian = true;   ///< first try the unprojected Hessian
  /// The iteration after one whose true Hessian failed goes straight to the projected Hessian. Where the true
  /// Hessian fails (cells turned inside out, contact) it mostly fails again one step later, and a failed try
  /// costs an assembly, a preconditioner set-up and linear iterations up to the negative curvature (Figure 1
  /// with contact: 0.96 of the time). false tries it at every iteration (more chances of a truncated step).
  bool skip_true_after_failure = true;
  int max_halvings = 60;
  /// Inexact Newton's largest forcing term: a solver that allows it (LinearSolver::inexact, mg and amg) solves
  /// each step to a residual min(forcing, √(‖g‖/‖g₀‖), η_model) ‖g‖ only, η_model being how far the last full
  /// step's linear model missed (newton.cpp). 0.1: on flesh the fewest Newton and CG iterations together
  /// (docs/results.md); the stretch test, whose Newton iterations cost more than its CG ones, uses 0.01.
  double forcing = 0.1;
  /// Called at the start of every iteration with its number (0 = the starting state) and ‖g‖.
  std::function<void(int iteration, double residual)> on_iteration;
  /// Asked at the start of every iteration; true stops the solve with `interrupted` set.
  std::function<bool()> should_stop;
};

struct NewtonReport {
  bool converged = false;
  bool converged_by_step = false; ///< converged by step_tolerance (before taking that last step)
  int iterations = 0;             ///< Newton steps taken
  int line_search_steps = 0;      ///< step halvings, in total
  int line_search_expansions = 0; ///< doublings of a full step whose slope stayed steep, in total
  int linear_iterations = 0;      ///< conjugate-gradient iterations, in total (0 for plain direct solves)
  int factorizations = 0;         ///< numeric factorizations by the linear solver (0 for PCG)
  int true_hessian_steps = 0;     ///< iterations that used the unprojected Hessian
  /// Of those, the steps an inexact solver truncated at a direction of negative curvature (truncated Newton,
  /// LinearSolver::last_truncated): the true Hessian was indefinite, and its step was taken all the same.
  int truncated_steps = 0;
  /// Iterations that solved with the last iteration's matrix (chord steps: an inexact solver, after a step
  /// within 30 times the step rule's bound), sparing an assembly and a preconditioner set-up.
  int chord_steps = 0;
  /// ‖d‖∞ of the last complete Newton direction (solved afresh, not truncated, not steepest descent): how far
  /// the solve was from its answer when it stopped (0 when it took none).
  double last_step = 0.0;
  double residual = 0.0;          ///< final ‖g‖
  double energy = 0.0;            ///< final energy
  std::vector<double> residuals;  ///< ‖g‖ at the start of each iteration and at the end
  double assembly_seconds = 0.0;
  double solve_seconds = 0.0;
  std::string failure;            ///< why it stopped without converging (empty when converged)
  bool interrupted = false;       ///< stopped because should_stop() said so
};

/// Minimises the problem (the elastic energy, or a time step's incremental potential, plus any other
/// terms) over its free DOFs (kinematic DOFs keep their values in x).
///   x  full DOF vector (3 #V); on return, the last accepted iterate
[[nodiscard]] NewtonReport newton_solve(Problem& problem, Eigen::VectorXd& x, LinearSolver& solver,
                                        const NewtonOptions& options = {});

}  // namespace snh
