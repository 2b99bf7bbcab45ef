#pragma once
// Sparse symmetric positive (semi-)definite solvers for the Newton step (docs/design.md), chosen by name
// from a registry (linear_solvers()):
//   cholmod  CHOLMOD supernodal Cholesky (default; symbolic analysis reused while the pattern is unchanged)
//   ldlt     Eigen's simplicial LDLᵀ
//   pcg      conjugate gradients with a Jacobi preconditioner
//   mg       conjugate gradients with a geometric multigrid V-cycle, for hex lattices (multigrid.hpp)
//   amg      conjugate gradients with a smoothed-aggregation multigrid V-cycle, any mesh (multigrid.hpp)
// A new solver is one more registry entry; the public conjugate gradients (conjugate_gradient.hpp) take
// any Preconditioner, and SolverGeometry carries what a geometric preconditioner (mg) needs to know about
// the mesh behind the matrix.
//
// Factor reuse (direct solvers, on by default): once a factorization exists, a later matrix with the
// same pattern is first solved by conjugate gradients preconditioned with that factor. Consecutive
// Newton matrices of a quasi-static or dynamic run differ little, so this converges in a few iterations,
// each costing one pair of triangular solves (at resolution 20 about 1/40 of a factorization). When it
// does not converge within LinearSolverOptions::reuse_iterations, or when the last reuse needed more
// than half of them, the matrix is factorized afresh. The answer is the same to the solve tolerance.
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/SparseCore>

#include "snh/mesh/volume_mesh.hpp"
#include "snh/solve/conjugate_gradient.hpp"

namespace snh {

struct LinearSolverOptions {
  std::string name = "cholmod";  ///< one of linear_solver_names()
  /// Relative residual ‖Ax − b‖ ≤ tolerance ‖b‖ at which conjugate gradients stop (PCG, and direct
  /// solvers reusing a factor).
  double tolerance = 1e-10;
  /// Direct solvers: precondition conjugate gradients with the last factor instead of refactorizing.
  bool reuse_factor = true;
  /// Direct solvers: conjugate-gradient iterations allowed with a reused factor before refactorizing.
  int reuse_iterations = 20;
};

/// What a preconditioner may need to know about the problem behind the matrix (a geometric multigrid:
/// the mesh and which DOF each row is). Pointers may be null (a matrix with no mesh behind it).
struct SolverGeometry {
  const VolumeMesh* mesh = nullptr;              ///< the simulated mesh at rest
  const std::vector<int>* free_index = nullptr;  ///< per DOF (3 #V), its row in the matrix; −1 where kinematic
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
  /// caller may accept an absolute residual `enough` (Newton: a tenth of its own tolerance). An inexact
  /// solver (inexact(): mg, amg) that meets non-positive curvature after try_factorize() and after at least
  /// one step of conjugate gradients, at an iterate x with ‖Ax − b‖ ≤ ½‖b‖, instead returns that x
  /// (truncated Newton: it minimises the quadratic model over the directions of positive curvature seen, so
  /// bᵀx > 0), and last_truncated() says so.
  [[nodiscard]] virtual Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough = 0.0) = 0;
  /// True when the last solve() stopped at a direction of non-positive curvature and returned the iterate
  /// before it (see solve()).
  [[nodiscard]] virtual bool last_truncated() const { return false; }
  /// Conjugate-gradient iterations of the last solve (0 for a plain direct solve).
  [[nodiscard]] virtual int last_iterations() const { return 0; }
  /// ‖A x − b‖ at the end of the last solve, as the iterative solver tracked it; NaN for a solver that does not
  /// (a direct solve, exact up to rounding).
  [[nodiscard]] virtual double last_residual() const { return std::numeric_limits<double>::quiet_NaN(); }
  /// Numeric factorizations so far (including shifted retries); 0 for PCG.
  [[nodiscard]] virtual int factorizations() const { return 0; }
  /// The registry name it was made under.
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// True for a solver whose Newton steps may be inexact (inexact Newton: the first steps, far from the
  /// answer, are solved only to a fraction of the residual; see newton_iterations).
  [[nodiscard]] virtual bool inexact() const { return false; }
};

/// The diagonal shifts a solver tries when A (lower triangle) is not positive definite: σ doubling from
/// 1e-10 of A's largest diagonal entry up to four times its largest absolute row sum (the Gershgorin bound,
/// with room), beyond which A + σI is positive definite, so only a non-finite A makes every try fail. Calls
/// attempt(σ) for each in turn and returns the first σ for which it returns true; NaN when none does.
[[nodiscard]] double search_diagonal_shift(const SparseLower& A, const std::function<bool(double)>& attempt);

/// "auto": the direct solver below this many free DOFs, multigrid from it (docs/solvers.md, "Linear solvers").
inline constexpr Eigen::Index kAutoIterativeFrom = 20000;
/// The registry name "auto" stands for: cholmod below kAutoIterativeFrom free DOFs, else mg on a hexahedral
/// lattice and amg on any other mesh.
[[nodiscard]] std::string_view auto_linear_solver(Eigen::Index free_dofs, bool hex_lattice);

/// One entry of the registry.
struct LinearSolverInfo {
  std::string_view name;
  std::string_view description;  ///< one line, for --help
  std::function<std::unique_ptr<LinearSolver>(const LinearSolverOptions&, const SolverGeometry&)> make;
};

/// Every linear solver, in the order --help lists them.
[[nodiscard]] const std::vector<LinearSolverInfo>& linear_solvers();
/// Their names.
[[nodiscard]] std::vector<std::string> linear_solver_names();
/// True if `name` is a registered solver.
[[nodiscard]] bool is_linear_solver(std::string_view name);

/// The solver called options.name. Throws std::invalid_argument for an unknown name (the message lists
/// the known ones) or bad options. PCG gives up (non-finite result) after max(1000, 2 n) iterations.
[[nodiscard]] std::unique_ptr<LinearSolver> make_linear_solver(const LinearSolverOptions& options,
                                                               const SolverGeometry& geometry = {});

}  // namespace snh
