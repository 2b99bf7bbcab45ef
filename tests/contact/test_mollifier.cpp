// The edge–edge mollifier: its derivatives by finite differences where it is active (nearly parallel
// edges, exactly parallel ones) and its values at and around the threshold.
#include <gtest/gtest.h>

#include "fd_check.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"

namespace snh::contact {
namespace {

using P4 = std::array<Vec3, 4>;

/// Edge a along x, edge b turned by angle from it in the x–z plane, both of length about 1.
P4 turned(double angle) {
  return {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.2, 0.3, 0.5), Vec3(0.2 + 1.1 * std::cos(angle), 0.3, 0.5 + 1.1 * std::sin(angle))};
}

TEST(Mollifier, ThresholdIsOneThousandthOfTheRestLengthsProduct) {
  const P4 x = turned(0.7);
  EXPECT_DOUBLE_EQ(edge_edge_mollifier_threshold(x[0], x[1], x[2], x[3]), 1e-3 * 1.0 * 1.21);
}

TEST(Mollifier, DerivativesWhereActive) {
  const P4 rest = turned(0.5);
  const double eps = edge_edge_mollifier_threshold(rest[0], rest[1], rest[2], rest[3]);
  const auto derivs = [eps](const P4& y) { return edge_edge_mollifier_derivatives(y[0], y[1], y[2], y[3], eps); };
  for (double angle : {2e-2, 1e-2, 1e-3, 1e-5}) {
    const P4 x = turned(angle);
    const auto m = derivs(x);
    EXPECT_GT(m.value, 0.0);
    EXPECT_LT(m.value, 1.0) << "active at angle " << angle;
    EXPECT_DOUBLE_EQ(m.value, edge_edge_mollifier(x[0], x[1], x[2], x[3], eps));
    test::expect_derivatives(derivs, x, "mollifier at angle " + std::to_string(angle));
  }
  // Random nearly parallel pairs in general position.
  std::mt19937_64 rng(11);
  for (int i = 0; i < 50; ++i) {
    const Vec3 a0 = test::random_point(rng), a1 = test::random_point(rng), b0 = test::random_point(rng);
    const Vec3 b1 = b0 + 0.8 * (a1 - a0) + 1e-3 * test::random_point(rng);
    const double e = edge_edge_mollifier_threshold(a0, a1, b0, b1);
    const auto d = [e](const P4& y) { return edge_edge_mollifier_derivatives(y[0], y[1], y[2], y[3], e); };
    ASSERT_LT(d({a0, a1, b0, b1}).value, 1.0);
    test::expect_derivatives(d, P4{a0, a1, b0, b1}, "random nearly parallel pair " + std::to_string(i));
  }
}

TEST(Mollifier, ZeroWhenParallelOneBeyondTheThreshold) {
  const P4 rest = turned(0.5);
  const double eps = edge_edge_mollifier_threshold(rest[0], rest[1], rest[2], rest[3]);
  const P4 parallel = turned(0.0);
  const auto m0 = edge_edge_mollifier_derivatives(parallel[0], parallel[1], parallel[2], parallel[3], eps);
  EXPECT_EQ(m0.value, 0.0);
  EXPECT_TRUE(m0.gradient.isZero());  // x = |a×b|² has a zero gradient at parallel edges
  const auto d = [eps](const P4& y) { return edge_edge_mollifier_derivatives(y[0], y[1], y[2], y[3], eps); };
  test::expect_derivatives(d, parallel, "mollifier at parallel edges");
  const P4 far = turned(0.3);
  const auto m1 = edge_edge_mollifier_derivatives(far[0], far[1], far[2], far[3], eps);
  EXPECT_EQ(m1.value, 1.0);
  EXPECT_TRUE(m1.gradient.isZero() && m1.hessian.isZero());
  // C¹ at the threshold: just below it, m is close to 1 and its gradient close to 0.
  const double at = std::asin(std::sqrt(eps) / 1.1);  // |a×b|² = 1.21 sin² = eps
  const P4 below = turned(at * (1 - 1e-6));
  const auto mb = edge_edge_mollifier_derivatives(below[0], below[1], below[2], below[3], eps);
  EXPECT_NEAR(mb.value, 1.0, 1e-10);
  const P4 half = turned(std::asin(std::sqrt(0.5 * eps) / 1.1));
  const auto mh = edge_edge_mollifier_derivatives(half[0], half[1], half[2], half[3], eps);
  EXPECT_NEAR(mh.value, 0.75, 1e-9);  // m(ε/2) = (2 − 1/2)/2
  EXPECT_LT(mb.gradient.norm(), 1e-4 * mh.gradient.norm()) << "m' → 0 at the threshold";
}

}  // namespace
}  // namespace snh::contact
