#pragma once
// Points for the contact terms' tests (tests only): plain vertices taken through weights.
#include <Eigen/Core>

#include "snh/fem/embedded_points.hpp"

namespace snh::testing {

/// Points 0 … n−1, point i as vertex i with weight 1 and vertex i + 1 (mod n) with weight 0: plain vertices
/// in value, but not plain (EmbeddedPoints::is_plain), so a term takes them through its weights.
inline EmbeddedPoints identity_through_weights(Eigen::Index n) {
  Eigen::MatrixXi vertex(2, n);
  Eigen::MatrixXd weight(2, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    vertex.col(i) << static_cast<int>(i), static_cast<int>((i + 1) % n);
    weight.col(i) << 1.0, 0.0;
  }
  return {vertex, weight, "test", n};
}

}  // namespace snh::testing
