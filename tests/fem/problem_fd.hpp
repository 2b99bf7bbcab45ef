#pragma once
// Finite-difference check of a Problem with respect to its free DOFs (tests only): the assembled gradient
// against differences of the energy, the assembled (unprojected) Hessian against differences of the
// gradient, each the best relative error over ε = 1e-3, 1e-4, 1e-5.
#include <algorithm>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "snh/fem/problem.hpp"
#include "snh/math/finite_difference.hpp"

namespace snh {

struct FdErrors {
  double gradient = 0.0, hessian = 0.0;
};

inline FdErrors problem_fd_errors(Problem& p, const Eigen::VectorXd& x) {
  Eigen::VectorXd g;
  HessianMatrix H;
  p.evaluate(x, g, &H, PsdProjection::none);
  const Eigen::MatrixXd Hd = Eigen::MatrixXd(H.matrix).selfadjointView<Eigen::Lower>();
  const DofMap& dofs = p.dofs();
  auto at = [&](const Eigen::VectorXd& y) {  // x with its free DOFs replaced by y
    Eigen::VectorXd z = x;
    for (Eigen::Index d = 0; d < z.size(); ++d)
      if (dofs.is_free(d)) z[d] = y[dofs.free_index()[d]];
    return z;
  };
  const Eigen::VectorXd y = dofs.gather_free(x);
  FdErrors best{1e300, 1e300};
  for (double eps : {1e-3, 1e-4, 1e-5}) {
    const Eigen::VectorXd fd_g = fd_gradient([&](const Eigen::VectorXd& z) { return p.energy(at(z)); }, y, eps);
    const Eigen::MatrixXd fd_H = fd_jacobian(
        [&](const Eigen::VectorXd& z) {
          Eigen::VectorXd gz;
          p.evaluate(at(z), gz, nullptr, PsdProjection::none);
          return gz;
        },
        y, eps);
    best.gradient = std::min(best.gradient, (fd_g - g).norm() / g.norm());
    best.hessian = std::min(best.hessian, (fd_H - Hd).norm() / Hd.norm());
  }
  return best;
}

/// The smallest eigenvalue of the assembled Hessian at x (with `projection`) over the Hessian's norm: ≥ −1e-9
/// or so for a PSD one (dense: small problems only).
inline double hessian_min_eigenvalue_ratio(Problem& p, const Eigen::VectorXd& x, PsdProjection projection) {
  Eigen::VectorXd g;
  HessianMatrix H;
  p.evaluate(x, g, &H, projection);
  const Eigen::MatrixXd Hd = Eigen::MatrixXd(H.matrix).selfadjointView<Eigen::Lower>();
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hd).eigenvalues().minCoeff() / Hd.norm();
}

/// The dense Hessian (both halves) and the gradient of one term over every DOF of x, all free.
inline std::pair<Eigen::MatrixXd, Eigen::VectorXd> assembled(Term& term, const Eigen::VectorXd& x, PsdProjection projection) {
  Problem problem(DofMap(std::vector<std::uint8_t>(static_cast<std::size_t>(x.size()), 0)));
  problem.add(term);
  Eigen::VectorXd g;
  HessianMatrix H;
  problem.evaluate(x, g, &H, projection);
  return {Eigen::MatrixXd(H.matrix).selfadjointView<Eigen::Lower>(), g};
}

}  // namespace snh
