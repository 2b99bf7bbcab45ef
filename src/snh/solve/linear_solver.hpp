#pragma once
// Sparse symmetric positive (semi-)definite solvers for the Newton step (DESIGN.md solve/):
// CHOLMOD supernodal Cholesky (default; symbolic analysis reused while the pattern is unchanged),
// Eigen's simplicial LDLT, and Jacobi-preconditioned conjugate gradients.
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

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  /// Prepares to solve with A (lower triangle of a symmetric matrix). The first call, and any call
  /// with a different pattern, runs the symbolic analysis. If A is not positive definite, a multiple of
  /// the identity is added (doubling from 1e-10 of the largest diagonal entry) until it is; the shift
  /// used is returned. Throws std::runtime_error if A has a non-finite entry.
  virtual double factorize(const SparseLower& A) = 0;
  /// Prepares A for solving only if it may be positive definite, without any shift. Direct solvers
  /// factorize and return false when A is not positive definite (then they hold no usable factor).
  /// PCG accepts A and finds out during solve(), which then returns a non-finite vector when it meets
  /// a direction of non-positive curvature.
  [[nodiscard]] virtual bool try_factorize(const SparseLower& A) = 0;
  /// x with A x = b for the last prepared A; non-finite entries if PCG found A indefinite.
  [[nodiscard]] virtual Eigen::VectorXd solve(const Eigen::VectorXd& b) = 0;
  /// Iterations of the last solve (PCG), 0 for direct solvers.
  [[nodiscard]] virtual int last_iterations() const { return 0; }
  [[nodiscard]] virtual LinearSolverKind kind() const = 0;
};

/// A solver of the given kind. pcg_tolerance is the relative residual at which PCG stops; PCG gives up
/// (non-finite result) after max(1000, 2 n) iterations.
[[nodiscard]] std::unique_ptr<LinearSolver> make_linear_solver(LinearSolverKind kind, double pcg_tolerance = 1e-10);

}  // namespace snh
