#include "snh/solve/linear_solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <fmt/format.h>

namespace snh {
namespace {

bool same_pattern(const SparseLower& a, const SparseLower& b) {
  if (a.rows() != b.rows() || a.nonZeros() != b.nonZeros()) return false;
  return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

/// Adds shift to the diagonal of a lower-triangular CSC matrix whose every column starts at its diagonal.
void add_to_diagonal(SparseLower& A, double shift) {
  for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
    const int first = A.outerIndexPtr()[c];
    if (A.outerIndexPtr()[c + 1] > first && A.innerIndexPtr()[first] == c) A.valuePtr()[first] += shift;
    else throw std::logic_error("add_to_diagonal: missing diagonal entry");
  }
}

/// Direct solvers share the symbolic-reuse and shift logic.
template <class Factor, LinearSolverKind K>
class DirectSolver final : public LinearSolver {
 public:
  DirectSolver() {
    // try_factorize expects indefinite matrices: keep CHOLMOD from printing a warning for each.
    if constexpr (requires(Factor& f) { f.cholmod(); }) factor_.cholmod().print = 0;
  }
  bool try_factorize(const SparseLower& A) override {
    if (!analysed_ || !same_pattern(A, pattern_)) {
      pattern_ = A;
      factor_.analyzePattern(A);
      analysed_ = true;
    }
    factor_.factorize(A);
    return factor_ok();
  }
  double factorize(const SparseLower& A) override {
    if (try_factorize(A)) return 0.0;
    // Shifts double from 1e-10 of the largest diagonal entry; beyond the Gershgorin bound (largest
    // absolute row sum) every shifted matrix is positive definite, so only a non-finite A can fail.
    Eigen::VectorXd row_abs = Eigen::VectorXd::Zero(A.rows());
    for (Eigen::Index c = 0; c < A.outerSize(); ++c)
      for (SparseLower::InnerIterator it(A, c); it; ++it) {
        row_abs[it.row()] += std::abs(it.value());
        if (it.row() != it.col()) row_abs[it.col()] += std::abs(it.value());
      }
    const double bound = 2.0 * std::max(row_abs.maxCoeff(), 1e-300);
    SparseLower shifted = A;
    double shift = 1e-10 * std::max(A.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    double applied = 0.0;
    while (std::isfinite(bound) && applied <= bound) {
      add_to_diagonal(shifted, shift - applied);
      applied = shift;
      factor_.factorize(shifted);
      if (factor_ok()) return applied;
      shift *= 2.0;
    }
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be factorized even with a diagonal shift "
                                         "of {:g} (it has a non-finite entry)",
                                         to_string(K), applied));
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) override { return factor_.solve(b); }
  LinearSolverKind kind() const override { return K; }

 private:
  /// The last factorization succeeded and (for LDLᵀ) every pivot is positive.
  bool factor_ok() const { return factor_.info() == Eigen::Success && positive_pivots(); }
  bool positive_pivots() const {
    if constexpr (requires(const Factor& f) { f.vectorD(); }) return (factor_.vectorD().array() > 0.0).all();
    else return true;  // LLᵀ fails by itself when not positive definite
  }
  Factor factor_;
  SparseLower pattern_;
  bool analysed_ = false;
};

/// Conjugate gradients with a Jacobi (diagonal) preconditioner on the lower-triangle-stored matrix.
/// Written out (rather than Eigen's) to detect non-positive curvature pᵀAp ≤ 0, which tells that A is
/// not positive definite: the Newton solver then falls back to the projected Hessian.
class PcgSolver final : public LinearSolver {
 public:
  explicit PcgSolver(double tolerance) : tolerance_(tolerance) {}
  bool try_factorize(const SparseLower& A) override {
    prepare(A);
    return true;
  }
  double factorize(const SparseLower& A) override {
    prepare(A);
    return 0.0;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) override {
    const Eigen::Index n = b.size();
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n), r = b;
    Eigen::VectorXd z = inv_diag_.cwiseProduct(r), p = z, Ap(n);
    double rz = r.dot(z);
    const double stop = tolerance_ * b.norm();
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, 2 * n));
    iterations_ = 0;
    while (r.norm() > stop) {
      if (iterations_ >= max_iterations) return Eigen::VectorXd::Constant(n, std::nan(""));
      ++iterations_;
      Ap.noalias() = A_.selfadjointView<Eigen::Lower>() * p;
      const double pAp = p.dot(Ap);
      if (!(pAp > 0.0)) return Eigen::VectorXd::Constant(n, std::nan(""));  // not positive definite
      const double alpha = rz / pAp;
      x.noalias() += alpha * p;
      r.noalias() -= alpha * Ap;
      z = inv_diag_.cwiseProduct(r);
      const double rz_next = r.dot(z);
      p = z + (rz_next / rz) * p;
      rz = rz_next;
    }
    return x;
  }
  int last_iterations() const override { return iterations_; }
  LinearSolverKind kind() const override { return LinearSolverKind::pcg; }

 private:
  void prepare(const SparseLower& A) {
    A_ = A;
    const Eigen::VectorXd d = A.diagonal();
    inv_diag_ = d.unaryExpr([](double v) { return v > 0.0 ? 1.0 / v : 1.0; });
  }
  double tolerance_;
  SparseLower A_;
  Eigen::VectorXd inv_diag_;
  int iterations_ = 0;
};

}  // namespace

std::string_view to_string(LinearSolverKind k) {
  switch (k) {
    case LinearSolverKind::cholmod: return "cholmod";
    case LinearSolverKind::ldlt: return "ldlt";
    case LinearSolverKind::pcg: return "pcg";
  }
  return "?";
}

std::optional<LinearSolverKind> parse_linear_solver(std::string_view s) {
  if (s == "cholmod") return LinearSolverKind::cholmod;
  if (s == "ldlt") return LinearSolverKind::ldlt;
  if (s == "pcg") return LinearSolverKind::pcg;
  return std::nullopt;
}

std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind, double pcg_tolerance) {
  switch (kind) {
    case LinearSolverKind::cholmod:
      return std::make_unique<DirectSolver<Eigen::CholmodSupernodalLLT<SparseLower, Eigen::Lower>, LinearSolverKind::cholmod>>();
    case LinearSolverKind::ldlt:
      return std::make_unique<DirectSolver<Eigen::SimplicialLDLT<SparseLower, Eigen::Lower>, LinearSolverKind::ldlt>>();
    case LinearSolverKind::pcg:
      return std::make_unique<PcgSolver>(pcg_tolerance);
  }
  throw std::invalid_argument("unknown linear solver");
}

}  // namespace snh
