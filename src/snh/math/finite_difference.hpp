#pragma once
// Central finite differences of functions of a 3x3 matrix, and the ε sweep used to check
// analytic derivatives (docs/design.md: every derivative is checked this way).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>

#include "snh/math/types.hpp"

namespace snh {

/// The ε values swept by best_relative_error: 1e-2 … 1e-8.
inline constexpr std::array<double, 7> kFiniteDifferenceSteps = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};

/// The fourth-order central stencil (−g(2ε) + 8g(ε) − 8g(−ε) + g(−2ε)) / 12ε, truncation error O(ε⁴),
/// for g(h) = the function at F + h e_k.
/// The result is evaluated (not an Eigen expression that would refer to the temporaries).
template <class At>
[[nodiscard]] auto fourth_order_difference(At&& at, double eps) -> std::decay_t<decltype(at(eps))> {
  return (-at(2 * eps) + 8.0 * at(eps) - 8.0 * at(-eps) + at(-2 * eps)) / (12.0 * eps);
}

/// F with h added to its k-th entry (column-major).
[[nodiscard]] inline Mat3 nudged(const Mat3& F, int k, double h) {
  Mat3 Fh = F;
  Fh.data()[k] += h;
  return Fh;
}

/// Fourth-order central difference of a scalar f(F): entry k is ∂f/∂F_k.
template <class Fn>
[[nodiscard]] Mat3 fd_gradient(Fn&& f, const Mat3& F, double eps) {
  Mat3 G;
  for (int k = 0; k < 9; ++k)
    G.data()[k] = fourth_order_difference([&](double h) { return f(nudged(F, k, h)); }, eps);
  return G;
}

/// Fourth-order central difference of a matrix-valued g(F): column k is ∂vec(g)/∂F_k.
template <class Fn>
[[nodiscard]] Mat9 fd_jacobian(Fn&& g, const Mat3& F, double eps) {
  Mat9 H;
  for (int k = 0; k < 9; ++k)
    H.col(k) = fourth_order_difference([&](double h) -> Vec9 { return vec(Mat3(g(nudged(F, k, h)))); }, eps);
  return H;
}

/// Fourth-order central difference of a scalar f(x) of a vector: entry i is ∂f/∂x_i.
template <class Fn>
[[nodiscard]] Eigen::VectorXd fd_gradient(Fn&& f, const Eigen::VectorXd& x, double eps) {
  Eigen::VectorXd G(x.size());
  for (Eigen::Index i = 0; i < x.size(); ++i)
    G[i] = fourth_order_difference(
        [&](double h) {
          Eigen::VectorXd xh = x;
          xh[i] += h;
          return static_cast<double>(f(xh));
        },
        eps);
  return G;
}

/// Fourth-order central difference of a vector-valued g(x) (m entries): column i (m by 1) is ∂g/∂x_i.
template <class Fn>
[[nodiscard]] Eigen::MatrixXd fd_jacobian(Fn&& g, const Eigen::VectorXd& x, double eps) {
  Eigen::MatrixXd H;
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const Eigen::VectorXd column = fourth_order_difference(
        [&](double h) -> Eigen::VectorXd {
          Eigen::VectorXd xh = x;
          xh[i] += h;
          return g(xh);
        },
        eps);
    if (i == 0) H.resize(column.size(), x.size());
    H.col(i) = column;
  }
  return H;
}

/// min over ε of ‖fd(ε) − analytic‖ / max(‖analytic‖, floor): the best relative error of a
/// finite-difference check. fd is called with each ε of kFiniteDifferenceSteps.
template <class Analytic, class Fd>
[[nodiscard]] double best_relative_error(const Analytic& analytic, Fd&& fd, double floor = 1e-8) {
  double best = std::numeric_limits<double>::infinity();
  const double denom = std::max(analytic.norm(), floor);
  for (double eps : kFiniteDifferenceSteps) {
    const double err = (fd(eps) - analytic).norm() / denom;
    if (std::isfinite(err)) best = std::min(best, err);
  }
  return best;
}

}  // namespace snh
