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

/// Conjugate gradients on the lower-triangle-stored A with the preconditioner apply (r ↦ M⁻¹r), from x = 0,
/// until ‖Ax − b‖ ≤ stop.
/// Written out (rather than Eigen's) to detect non-positive curvature pᵀAp ≤ 0, which proves that A is
/// not positive definite: the Newton solver then falls back to the projected Hessian.
enum class CgStatus { converged, indefinite, exhausted };
template <class Precondition>
CgStatus conjugate_gradients(const SparseLower& A, const Eigen::VectorXd& b, Precondition&& apply, double stop,
                             int max_iterations, Eigen::VectorXd& x, int& iterations) {
  const Eigen::Index n = b.size();
  x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd r = b, z = apply(r), p = z, Ap(n);
  double rz = r.dot(z);
  iterations = 0;
  while (r.norm() > stop) {
    if (iterations >= max_iterations) return CgStatus::exhausted;
    ++iterations;
    Ap.noalias() = A.selfadjointView<Eigen::Lower>() * p;
    const double pAp = p.dot(Ap);
    if (!(pAp > 0.0)) return CgStatus::indefinite;
    const double alpha = rz / pAp;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * Ap;
    z = apply(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return CgStatus::converged;
}

Eigen::VectorXd not_a_solution(Eigen::Index n) { return Eigen::VectorXd::Constant(n, std::nan("")); }

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
    return numeric(A);
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
      if (numeric(shifted)) return applied;
      shift *= 2.0;
    }
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be factorized even with a diagonal shift "
                                         "of {:g} (it has a non-finite entry)",
                                         to_string(K), applied));
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double /*enough*/) override { return factor_.solve(b); }
  int factorizations() const override { return factorizations_; }
  LinearSolverKind kind() const override { return K; }

 private:
  /// Factorizes A (pattern analysed); true if it succeeded and (for LDLᵀ) every pivot is positive.
  bool numeric(const SparseLower& A) {
    ++factorizations_;
    factor_.factorize(A);
    return factor_.info() == Eigen::Success && positive_pivots();
  }
  bool positive_pivots() const {
    if constexpr (requires(const Factor& f) { f.vectorD(); }) return (factor_.vectorD().array() > 0.0).all();
    else return true;  // LLᵀ fails by itself when not positive definite
  }
  Factor factor_;
  SparseLower pattern_;
  bool analysed_ = false;
  int factorizations_ = 0;
};

/// A direct solver whose last factor preconditions conjugate gradients on later matrices of the same
/// pattern, refactorizing only when that stops paying (see the header).
class FactorReuse final : public LinearSolver {
 public:
  FactorReuse(std::unique_ptr<LinearSolver> direct, double tolerance, int max_iterations)
      : direct_(std::move(direct)), tolerance_(tolerance), max_iterations_(max_iterations) {}
  bool try_factorize(const SparseLower& A) override { return prepare(A, Mode::reuse_try) || fresh(Mode::direct_try); }
  double factorize(const SparseLower& A) override {
    if (prepare(A, Mode::reuse_must)) return 0.0;
    fresh(Mode::direct_must);
    return shift_;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    iterations_ = 0;
    if (mode_ == Mode::direct_try || mode_ == Mode::direct_must) return direct_->solve(b);
    Eigen::VectorXd x;
    const CgStatus status = conjugate_gradients(
        A_, b, [this](const Eigen::VectorXd& r) { return direct_->solve(r); },
        std::max(tolerance_ * b.norm(), enough), max_iterations_, x, iterations_);
    if (status == CgStatus::converged) {
      stale_ = 2 * iterations_ > max_iterations_;  // the factor is drifting away: refresh it next time
      return x;
    }
    // A proven indefinite after try_factorize: report it (the factor stays a good preconditioner).
    if (status == CgStatus::indefinite && mode_ == Mode::reuse_try) return not_a_solution(b.size());
    // Too slow, or indefinite where a solution is required: factorize this matrix.
    if (!fresh(mode_ == Mode::reuse_try ? Mode::direct_try : Mode::direct_must)) return not_a_solution(b.size());
    return direct_->solve(b);
  }
  int last_iterations() const override { return iterations_; }
  int factorizations() const override { return direct_->factorizations(); }
  LinearSolverKind kind() const override { return direct_->kind(); }

 private:
  enum class Mode { direct_try, direct_must, reuse_try, reuse_must };
  /// Takes A; true if the held factor can precondition it (then mode becomes `reuse`).
  bool prepare(const SparseLower& A, Mode reuse) {
    const bool reusable = have_factor_ && !stale_ && same_pattern(A, A_);
    if (reusable) std::copy(A.valuePtr(), A.valuePtr() + A.nonZeros(), A_.valuePtr());
    else A_ = A;
    mode_ = reuse;
    return reusable;
  }
  /// Factorizes A_ (shifted if `direct_must`); false if A_ is not positive definite (`direct_try`).
  bool fresh(Mode direct) {
    mode_ = direct;
    stale_ = false;
    shift_ = 0.0;
    if (direct == Mode::direct_must) {
      shift_ = direct_->factorize(A_);
      have_factor_ = true;
    } else {
      have_factor_ = direct_->try_factorize(A_);
    }
    return have_factor_;
  }
  std::unique_ptr<LinearSolver> direct_;
  double tolerance_;
  int max_iterations_;
  SparseLower A_;
  Mode mode_ = Mode::direct_try;
  bool have_factor_ = false, stale_ = false;
  double shift_ = 0.0;
  int iterations_ = 0;
};

/// Conjugate gradients with a Jacobi (diagonal) preconditioner.
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
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, 2 * b.size()));
    Eigen::VectorXd x;
    const CgStatus status = conjugate_gradients(
        A_, b, [this](const Eigen::VectorXd& r) { return Eigen::VectorXd(inv_diag_.cwiseProduct(r)); },
        std::max(tolerance_ * b.norm(), enough), max_iterations, x, iterations_);
    return status == CgStatus::converged ? x : not_a_solution(b.size());
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

std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& o) {
  if (!(o.tolerance > 0.0)) throw std::invalid_argument("linear solver tolerance must be > 0");
  if (o.reuse_iterations < 1) throw std::invalid_argument("reuse_iterations must be >= 1");
  std::unique_ptr<LinearSolver> direct;
  switch (o.kind) {
    case LinearSolverKind::cholmod:
      direct = std::make_unique<DirectSolver<Eigen::CholmodSupernodalLLT<SparseLower, Eigen::Lower>, LinearSolverKind::cholmod>>();
      break;
    case LinearSolverKind::ldlt:
      direct = std::make_unique<DirectSolver<Eigen::SimplicialLDLT<SparseLower, Eigen::Lower>, LinearSolverKind::ldlt>>();
      break;
    case LinearSolverKind::pcg: return std::make_unique<PcgSolver>(o.tolerance);
  }
  if (!direct) throw std::invalid_argument("unknown linear solver");
  if (!o.reuse_factor) return direct;
  return std::make_unique<FactorReuse>(std::move(direct), o.tolerance, o.reuse_iterations);
}

}  // namespace snh
