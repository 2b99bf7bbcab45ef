#include "snh/solve/conjugate_gradient.hpp"

namespace snh {

void JacobiPreconditioner::compute(const SparseLower& A) {
  const Eigen::VectorXd d = A.diagonal();
  inverse_diagonal_ = d.unaryExpr([](double v) { return v > 0.0 ? 1.0 / v : 1.0; });
}

namespace {

template <class Product>
CgResult cg(const Product& product, const Eigen::VectorXd& b, const Preconditioner& M, double stop, int max_iterations,
            Eigen::VectorXd& x) {
  const Eigen::Index n = b.size();
  CgResult result;
  x = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd r = b, z, Ap(n);
  M.apply(r, z);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  while ((result.residual = r.norm()) > stop) {
    if (result.iterations >= max_iterations) {
      result.status = CgStatus::exhausted;
      return result;
    }
    ++result.iterations;
    product(p, Ap);
    const double pAp = p.dot(Ap);
    if (!(pAp > 0.0)) {
      result.status = CgStatus::indefinite;
      return result;
    }
    const double alpha = rz / pAp;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * Ap;
    M.apply(r, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  return result;
}

}  // namespace

CgResult conjugate_gradients(const SparseLower& A, const Eigen::VectorXd& b, const Preconditioner& M, double stop,
                             int max_iterations, Eigen::VectorXd& x) {
  const auto product = [&A](const Eigen::VectorXd& p, Eigen::VectorXd& Ap) { Ap.noalias() = A.selfadjointView<Eigen::Lower>() * p; };
  return cg(product, b, M, stop, max_iterations, x);
}

CgResult conjugate_gradients(const MatrixProduct& A, const Eigen::VectorXd& b, const Preconditioner& M, double stop,
                             int max_iterations, Eigen::VectorXd& x) {
  return cg(A, b, M, stop, max_iterations, x);
}

}  // namespace snh
