#pragma once
// Sparse symmetric positive (semi-)definite solvers for the Newton step (DESIGN.md solve/):
// CHOLMOD supernodal Cholesky (default; symbolic analysis reused while the pattern is unchanged),
// Eigen's simplicial LDLT, and Jacobi-preconditioned conjugate gradients.
//
// Factor reuse (direct solvers, on by default): once a factorization exists, a later matrix with the
// same pattern is first solved by conjugate gradients preconditioned with that factor. Consecutive
// Newton matrices of a quasi-static or dynamic run differ little, so this converges in a few iterations,
// each costing one pair of triangular solves (at resolution 20 about 1/40 of a factorization). When it
// does not converge within LinearSolverOptions::reuse_iterations, or when the last reuse needed more
// than half of them, the matrix is factorized afresh. The answer is the same to the solve tolerance.
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/SparseCore>

namespace snh {

using SparseLower = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

enum class LinearSolverKind { cholmod, ldlt, pcg };

[[nodiscard]] std::string_view to_string(LinearSolverKind k);
/// "cholmod", "ldlt" or "pcg"; nullopt otherwise.
[[nodiscard]] std::optional<LinearSolverKind> parse_linear_solver(std::string_view s);

struct LinearSolverOptions {
  LinearSolverKind kind = LinearSolverKind::cholmod;
  /// Relative residual ‖Ax − b‖ ≤ tolerance ‖b‖ at which conjugate gradients stop (PCG, and direct
  /// solvers reusing a factor).
  double tolerance = 1e-10;
  /// Direct solvers: precondition conjugate gradients with the last factor instead of refactorizing.
  bool reuse_factor = true;
  /// Direct solvers: conjugate-gradient iterations allowed with a reused factor before refactorizing.
  int reuse_iterations = 20;
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Prepares to solve with A (lower triangle of a symmetric matrix). The first call, and any call
  /// with a different pattern, runs the symbolic analysis. If A is not positive definite, a multiple of
  /// the identity is added (doubling from 1e-10 of the largest diagonal entry) until it is; the shift
  /// used is returned (0 when a reused factor will precondition the solve). Throws std::runtime_error if
  /// A has a non-finite entry.
  virtual double factorize(const SparseLower& A) = 0;
  /// Prepares A for solving only if it may be positive definite, without any shift. Direct solvers
  /// factorize and return false when A is not positive definite (then they hold no usable factor).
  /// PCG, and a direct solver reusing its factor, accept A and find out during solve(), which then
  /// returns a non-finite vector when it meets a direction of non-positive curvature.
  [[nodiscard]] virtual bool try_factorize(const SparseLower& A) = 0;
  /// x with A x = b for the last prepared A; non-finite entries if A turned out not positive definite
  /// after try_factorize(). Conjugate gradients stop at ‖Ax − b‖ ≤ max(tolerance ‖b‖, enough): the
  /// caller may accept an absolute residual `enough` (Newton: a tenth of its own tolerance).
  [[nodiscard]] virtual Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough = 0.0) = 0;
  /// Conjugate-gradient iterations of the last solve (0 for a plain direct solve).
  [[nodiscard]] virtual int last_iterations() const { return 0; }
  /// Numeric factorizations so far (including shifted retries); 0 for PCG.
  [[nodiscard]] virtual int factorizations() const { return 0; }
  [[nodiscard]] virtual LinearSolverKind kind() const = 0;
};

/// A solver with the given options. PCG gives up (non-finite result) after max(1000, 2 n) iterations.
[[nodiscard]] std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& options);
[[nodiscard]] inline std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind) {
  return make_linear_solver(LinearSolverOptions{.kind = kind});
}

}  // namespace snh
