#pragma once
// Seeded random samples of 3x3 matrices for tests and measurements.
#include <random>

#include <Eigen/Geometry>

#include "snh/math/types.hpp"

namespace snh {

/// A uniformly distributed rotation (det = +1), from a normalised Gaussian quaternion.
template <class Rng>
[[nodiscard]] Mat3 random_rotation(Rng& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

/// U diag(sigma) Vᵀ with U, V random rotations: a matrix with exactly these signed singular values.
template <class Rng>
[[nodiscard]] Mat3 random_matrix_with_sigma(Rng& rng, const Vec3& sigma) {
  return random_rotation(rng) * sigma.asDiagonal() * random_rotation(rng).transpose();
}

/// A matrix with entries uniform in [lo, hi].
template <class Rng>
[[nodiscard]] Mat3 random_matrix(Rng& rng, double lo = -1.0, double hi = 1.0) {
  std::uniform_real_distribution<double> u(lo, hi);
  Mat3 F;
  for (int k = 0; k < 9; ++k) F.data()[k] = u(rng);
  return F;
}

}  // namespace snh
