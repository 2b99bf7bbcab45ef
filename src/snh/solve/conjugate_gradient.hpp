#pragma once
// Preconditioned conjugate gradients on a symmetric matrix stored as its lower triangle (docs/design.md),
// written out (rather than Eigen's) to detect non-positive curvature pᵀAp ≤ 0, which proves that the
// matrix is not positive definite: Newton then falls back to the projected Hessian. The preconditioner is
// an interface so that a direct factor (factor reuse), Jacobi, and later multigrid plug in the same way.
#include <functional>

#include <Eigen/Core>

#include "snh/math/sparse.hpp"

namespace snh {

/// z = M⁻¹ r for a symmetric positive definite M that approximates A.
class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  ///   r  residual (n)
  ///   z  overwritten with M⁻¹ r (n)
  virtual void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const = 0;
};

/// M = diag(A), with 1 where a diagonal entry is not positive.
class JacobiPreconditioner final : public Preconditioner {
 public:
  JacobiPreconditioner() = default;
  explicit JacobiPreconditioner(const SparseLower& A) { compute(A); }
  void compute(const SparseLower& A);
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override { z = inverse_diagonal_.cwiseProduct(r); }

 private:
  Eigen::VectorXd inverse_diagonal_;
};

enum class CgStatus {
  converged,   ///< ‖Ax − b‖ ≤ stop
  indefinite,  ///< a direction with pᵀAp ≤ 0 was met: A is not positive definite
  exhausted,   ///< max_iterations reached first
};

struct CgResult {
  CgStatus status = CgStatus::converged;
  int iterations = 0;
  double residual = 0.0;  ///< ‖b − A x‖ of the returned x (as the iteration updated it)
};

/// Solves A x = b from x = 0 until ‖Ax − b‖ ≤ stop.
///   A               lower triangle of a symmetric matrix (n by n)
///   b               right-hand side (n)
///   M               preconditioner
///   stop            absolute residual norm at which to stop
///   max_iterations  iterations allowed
///   x               overwritten with the last iterate (n)
[[nodiscard]] CgResult conjugate_gradients(const SparseLower& A, const Eigen::VectorXd& b, const Preconditioner& M,
                                           double stop, int max_iterations, Eigen::VectorXd& x);

/// Ap = A p for a symmetric matrix held in another form (multigrid: 3×3 nodal blocks).
using MatrixProduct = std::function<void(const Eigen::VectorXd& p, Eigen::VectorXd& Ap)>;
/// The same with A given by its product.
[[nodiscard]] CgResult conjugate_gradients(const MatrixProduct& A, const Eigen::VectorXd& b, const Preconditioner& M,
                                           double stop, int max_iterations, Eigen::VectorXd& x);

}  // namespace snh
