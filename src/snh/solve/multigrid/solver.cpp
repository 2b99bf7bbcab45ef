// The registry's "mg" and "amg" (multigrid.hpp): conjugate gradients preconditioned by the V-cycle, with the
// direct solvers' diagonal shift for matrices that are not positive definite, truncated Newton steps, and
// coarse levels kept across Newton matrices while they serve.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "snh/solve/multigrid.hpp"

namespace snh {
namespace {

class MultigridSolver final : public LinearSolver {
 public:
  MultigridSolver(const LinearSolverOptions& o, const SolverGeometry& g, Coarsening how)
      : how_(how), name_(how == Coarsening::lattice ? "mg" : "amg"), tolerance_(o.tolerance), vcycle_(mesh_of(g, name_), *g.free_index, how) {}
  bool try_factorize(const SparseLower& A) override {
    may_truncate_ = true;
    return compute(A);
  }
  double factorize(const SparseLower& A) override {
    may_truncate_ = false;
    if (compute(A)) return 0.0;
    // The direct solvers' search (linear_solver.hpp), on the V-cycle of A + σI.
    const double shift = search_diagonal_shift(A, [&](double s) { return vcycle_.compute(A, s); });
    if (!std::isnan(shift)) return shift;
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be made positive definite by a diagonal shift (it has a non-finite entry)", name_));
  }
  /// Conjugate gradients on the matrix the V-cycle holds (A, plus the shift factorize() added).
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, b.size() / 10));
    Eigen::VectorXd x;
    const MatrixProduct A = [this](const Eigen::VectorXd& p, Eigen::VectorXd& Ap) { vcycle_.multiply(p, Ap); };
    const CgResult r = conjugate_gradients(A, b, vcycle_, std::max(tolerance_ * b.norm(), enough), max_iterations, x);
    iterations_ = r.iterations;
    residual_ = r.residual;
    if (fresh_iterations_ < 0) fresh_iterations_ = r.iterations;
    // Truncated Newton (Nocedal and Wright, Algorithm 7.1): a matrix given to try_factorize() that shows
    // negative curvature after the first CG step yields the iterate before it, if that already solves the
    // system to half of ‖b‖ (an inexact Newton step of forcing ½): a step of the true Hessian where it is
    // indefinite, rather than a failed true step and a fall-back to the projected Hessian, whose steps converge
    // slowly on inverted cells. The residual rule refuses truncated iterates that solve the system poorly:
    // those cost more Newton iterations than no truncation (a box squashed through itself,
    // tests/solve/test_multigrid.cpp).
    truncated_ = may_truncate_ && r.status == CgStatus::indefinite && r.iterations > 1 && r.residual <= 0.5 * b.norm();
    if (truncated_) return x;
    return r.status == CgStatus::converged ? x : Eigen::VectorXd::Constant(b.size(), std::nan(""));
  }
  bool last_truncated() const override { return truncated_; }
  int last_iterations() const override { return iterations_; }
  double last_residual() const override { return residual_; }
  std::string_view name() const override { return name_; }
  bool inexact() const override { return true; }

 private:
  static const VolumeMesh& mesh_of(const SolverGeometry& g, std::string_view name) {
    if (!g.mesh || !g.free_index)
      throw std::invalid_argument(fmt::format("the multigrid solver ({}) needs the mesh behind the matrix (use cholmod, ldlt or pcg)", name));
    return *g.mesh;
  }
  /// The V-cycle for A. Both keep their coarse levels (the costly part: the Galerkin products, amg's smoothed
  /// P, the coarsest factorization) from an earlier Newton matrix while the last solve needed at most half
  /// as many iterations again as the first solve after they were made: consecutive Newton matrices differ
  /// little, so older coarse levels still serve, and remaking them for every matrix costs more than the few
  /// iterations it saves.
  bool compute(const SparseLower& A) {
    const bool coarse = fresh_iterations_ < 0 || 2 * iterations_ > 3 * fresh_iterations_;
    if (coarse) fresh_iterations_ = -1;
    if (vcycle_.compute(A, 0.0, coarse)) return true;
    fresh_iterations_ = -1;  // factorize() then shifts: the coarse levels are made for each shifted try
    return false;
  }
  Coarsening how_;
  std::string_view name_;
  double tolerance_;
  int fresh_iterations_ = -1;  ///< iterations of the first solve with the current coarse levels (−1: none yet)
  MultigridPreconditioner vcycle_;
  int iterations_ = 0;
  double residual_ = std::nan("");
  bool may_truncate_ = false;  ///< the matrix came from try_factorize() (it may be indefinite)
  bool truncated_ = false;     ///< the last solve was truncated at non-positive curvature
};

}  // namespace

std::unique_ptr<LinearSolver> make_multigrid_solver(const LinearSolverOptions& options, const SolverGeometry& geometry) {
  return std::make_unique<MultigridSolver>(options, geometry, Coarsening::lattice);
}

bool amg_applicable(const SolverGeometry& geometry) {
  return geometry.mesh && geometry.free_index && geometry.free_index->size() == 3 * static_cast<std::size_t>(geometry.mesh->vertex_count());
}

std::unique_ptr<LinearSolver> make_amg_solver(const LinearSolverOptions& options, const SolverGeometry& geometry) {
  return std::make_unique<MultigridSolver>(options, geometry, Coarsening::aggregation);
}

}  // namespace snh
