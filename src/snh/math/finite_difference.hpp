#pragma once
// Central finite differences of functions of a 3x3 matrix, and the ε sweep used to check
// analytic derivatives (DESIGN.md: every derivative is checked this way).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "snh/math/types.hpp"

namespace snh {

/// The ε values swept by best_relative_error: 1e-2 … 1e-8.
inline constexpr std::array<double, 7> kFiniteDifferenceSteps = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};

/// Fourth-order central difference of a scalar f(F): entry (i, j) is
/// (−f(F + 2εe_ij) + 8f(F + εe_ij) − 8f(F − εe_ij) + f(F − 2εe_ij)) / 12ε (truncation error O(ε⁴)).
template <class Fn>
[[nodiscard]] Mat3 fd_gradient(Fn&& f, const Mat3& F, double eps) {
  Mat3 G;
  for (int k = 0; k < 9; ++k) {
    auto at = [&](double h) {
      Mat3 Fh = F;
      Fh.data()[k] += h;
      return f(Fh);
    };
    G.data()[k] = (-at(2 * eps) + 8.0 * at(eps) - 8.0 * at(-eps) + at(-2 * eps)) / (12.0 * eps);
  }
  return G;
}

/// Fourth-order central difference of a matrix-valued g(F): column k is the derivative of vec(g)
/// along e_k, with the stencil of fd_gradient.
template <class Fn>
[[nodiscard]] Mat9 fd_jacobian(Fn&& g, const Mat3& F, double eps) {
  Mat9 H;
  for (int k = 0; k < 9; ++k) {
    auto at = [&](double h) {
      Mat3 Fh = F;
      Fh.data()[k] += h;
      return vec(Mat3(g(Fh)));
    };
    H.col(k) = (-at(2 * eps) + 8.0 * at(eps) - 8.0 * at(-eps) + at(-2 * eps)) / (12.0 * eps);
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
