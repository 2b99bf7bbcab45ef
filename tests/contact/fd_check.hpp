#pragma once
// Finite-difference checks of the contact library's fixed-size derivatives (tests/contact).
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <string>

#include "snh/contact/distance_core.hpp"
#include "snh/math/finite_difference.hpp"

namespace snh::contact::test {

/// The 3M coordinates of M points stacked.
template <std::size_t M>
Eigen::VectorXd stack(const std::array<Vec3, M>& x) {
  Eigen::VectorXd v(3 * M);
  for (std::size_t i = 0; i < M; ++i) v.segment<3>(3 * i) = x[i];
  return v;
}
template <std::size_t M>
std::array<Vec3, M> unstack(const Eigen::VectorXd& v) {
  std::array<Vec3, M> x;
  for (std::size_t i = 0; i < M; ++i) x[i] = v.segment<3>(3 * i);
  return x;
}

/// Checks that derivatives(x) has value value(x), gradient = FD(value) and Hessian = FD(gradient), with
/// ε swept and the best error relative to max(‖analytic‖, floor) at most tol.
template <std::size_t M, class Derivs>
void expect_derivatives(Derivs&& derivatives, const std::array<Vec3, M>& x, const std::string& where,
                        double tol = 1e-6, double floor = 1e-6) {
  const auto D = derivatives(x);
  ASSERT_TRUE(std::isfinite(D.value) && D.gradient.allFinite() && D.hessian.allFinite()) << where;
  const Eigen::VectorXd x0 = stack(x);
  const auto value = [&](const Eigen::VectorXd& y) { return derivatives(unstack<M>(y)).value; };
  const auto gradient = [&](const Eigen::VectorXd& y) -> Eigen::VectorXd {
    return derivatives(unstack<M>(y)).gradient;
  };
  const Eigen::VectorXd g = D.gradient;
  const Eigen::MatrixXd H = D.hessian;
  const double eg = best_relative_error(g, [&](double eps) { return fd_gradient(value, x0, eps); }, floor);
  const double eh = best_relative_error(H, [&](double eps) { return fd_jacobian(gradient, x0, eps); }, floor);
  EXPECT_LE(eg, tol) << "gradient vs FD, " << where << "\n x = " << x0.transpose();
  EXPECT_LE(eh, tol) << "Hessian vs FD, " << where << "\n x = " << x0.transpose();
  EXPECT_LE((H - H.transpose()).norm(), 1e-12 * std::max(1.0, H.norm())) << "Hessian symmetric, " << where;
}

inline Vec3 random_point(std::mt19937_64& rng, double lo = -1.0, double hi = 1.0) {
  std::uniform_real_distribution<double> u(lo, hi);
  return Vec3(u(rng), u(rng), u(rng));
}

}  // namespace snh::contact::test
