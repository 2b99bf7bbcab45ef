#include "snh/solve/linear_solver.hpp"

#include <algorithm>
#include <stdexcept>

#include <Eigen/CholmodSupport>
#include <Eigen/IterativeLinearSolvers>
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
    return factor_.info() == Eigen::Success && positive_pivots();
  }
  double factorize(const SparseLower& A) override {
    if (try_factorize(A)) return 0.0;
    const double diag = A.diagonal().cwiseAbs().maxCoeff();
    SparseLower shifted = A;
    double shift = 1e-10 * std::max(diag, 1e-300);
    double applied = 0.0;
    while (shift <= std::max(diag, 1e-300)) {
      add_to_diagonal(shifted, shift - applied);
      applied = shift;
      factor_.factorize(shifted);
      if (factor_.info() == Eigen::Success && positive_pivots()) return applied;
      shift *= 2.0;
    }
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be factorized even with a diagonal shift "
                                         "of {:g} (it has a non-finite entry or is far from positive definite)",
                                         to_string(K), applied));
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) override { return factor_.solve(b); }
  LinearSolverKind kind() const override { return K; }

 private:
  bool positive_pivots() const {
    if constexpr (requires(const Factor& f) { f.vectorD(); }) return (factor_.vectorD().array() > 0.0).all();
    else return true;  // LLᵀ fails by itself when not positive definite
  }
  Factor factor_;
  SparseLower pattern_;
  bool analysed_ = false;
};

class PcgSolver final : public LinearSolver {
 public:
  explicit PcgSolver(double tolerance) { cg_.setTolerance(tolerance); }
  bool try_factorize(const SparseLower&) override { return false; }
  double factorize(const SparseLower& A) override {
    // (A multi-threaded product with both triangles stored row-major was measured: no faster at
    // res 20 and slower at res 10, where waking the threads every iteration costs more than it saves.)
    A_ = A;
    cg_.compute(A_);
    return 0.0;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b) override {
    Eigen::VectorXd x = cg_.solve(b);
    iterations_ = static_cast<int>(cg_.iterations());
    return x;
  }
  int last_iterations() const override { return iterations_; }
  LinearSolverKind kind() const override { return LinearSolverKind::pcg; }

 private:
  SparseLower A_;
  Eigen::ConjugateGradient<SparseLower, Eigen::Lower, Eigen::DiagonalPreconditioner<double>> cg_;
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
