// A pair's barrier energy (point–triangle, and mollified edge–edge) by finite differences at random
// configurations within d̂, nearly parallel edges included; zero out of range, +∞ in contact; the
// projected Hessian is the PSD projection of the true one.
#include <gtest/gtest.h>

#include <random>

#include "fd_check.hpp"
#include "snh/contact/barrier.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"
#include "snh/contact/pair_barrier.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {
namespace {

using P4 = std::array<Vec3, 4>;
constexpr double kDhat = 0.5, kShat = kDhat * kDhat;

TEST(PairBarrier, PointTriangleByFiniteDifferences) {
  std::mt19937_64 rng(51);
  int active = 0;
  for (int i = 0; i < 400 && active < 60; ++i) {
    const P4 x = {test::random_point(rng, -0.6, 0.6), test::random_point(rng), test::random_point(rng),
                  test::random_point(rng)};
    const double s = point_triangle_distance(x[0], x[1], x[2], x[3]);
    if (s >= kShat) continue;
    ++active;
    const auto energy = [](const P4& y) { return point_triangle_barrier(y[0], y[1], y[2], y[3], kShat, false); };
    EXPECT_NEAR(energy(x).value, barrier(s, kShat), 1e-14);
    test::expect_derivatives(energy, x, "point-triangle barrier, sample " + std::to_string(i), 1e-6, 1e-8);
  }
  EXPECT_GE(active, 60);
}

TEST(PairBarrier, EdgeEdgeByFiniteDifferences) {
  std::mt19937_64 rng(52);
  int active = 0, mollified = 0;
  for (int i = 0; i < 1200 && active < 120; ++i) {
    P4 x = {test::random_point(rng), test::random_point(rng), test::random_point(rng), test::random_point(rng)};
    // Every other sample: b nearly parallel to a (the mollifier active).
    const double eps = edge_edge_mollifier_threshold(x[0], x[1], x[2], x[3]);
    if (i % 2) x[3] = x[2] + 0.9 * (x[1] - x[0]) + 0.01 * test::random_point(rng);
    const double s = edge_edge_distance(x[0], x[1], x[2], x[3]);
    if (s >= kShat || s < 1e-6) continue;
    ++active;
    const double m = edge_edge_mollifier(x[0], x[1], x[2], x[3], eps);
    mollified += m < 1.0;
    const auto energy = [eps](const P4& y) { return edge_edge_barrier(y[0], y[1], y[2], y[3], kShat, eps, false); };
    EXPECT_NEAR(energy(x).value, m * barrier(s, kShat), 1e-14);
    test::expect_derivatives(energy, x, "edge-edge barrier, sample " + std::to_string(i), 1e-6, 1e-8);
  }
  EXPECT_GE(active, 120);
  EXPECT_GE(mollified, 20);
}

TEST(PairBarrier, ZeroOutOfRangeInfiniteInContact) {
  const Vec3 t0(0, 0, 0), t1(1, 0, 0), t2(0, 1, 0);
  for (double h : {kDhat, 2 * kDhat}) {
    const auto b = point_triangle_barrier(Vec3(0.2, 0.2, h), t0, t1, t2, kShat, true);
    EXPECT_EQ(b.value, 0.0);
    EXPECT_TRUE(b.gradient.isZero() && b.hessian.isZero());
  }
  EXPECT_EQ(point_triangle_barrier(Vec3(0.2, 0.2, 0), t0, t1, t2, kShat, true).value,
            std::numeric_limits<double>::infinity());
  const auto e = edge_edge_barrier(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, -1, 0), Vec3(0.5, 1, 0), kShat, 1e-3, true);
  EXPECT_EQ(e.value, std::numeric_limits<double>::infinity());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(point_triangle_barrier(Vec3(0.2, nan, 0.1), t0, t1, t2, kShat, true).value));
}

TEST(PairBarrier, ProjectedHessianIsThePsdPart) {
  std::mt19937_64 rng(53);
  int indefinite = 0;
  for (int i = 0; i < 300; ++i) {
    const P4 x = {test::random_point(rng, -0.6, 0.6), test::random_point(rng), test::random_point(rng),
                  test::random_point(rng)};
    const auto raw = point_triangle_barrier(x[0], x[1], x[2], x[3], kShat, false);
    const auto projected = point_triangle_barrier(x[0], x[1], x[2], x[3], kShat, true);
    EXPECT_EQ(raw.value, projected.value);
    EXPECT_EQ(raw.gradient, projected.gradient);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> er{Eigen::MatrixXd(raw.hessian)},
        ep{Eigen::MatrixXd(projected.hessian)};
    const double scale = std::max(1.0, raw.hessian.norm());
    EXPECT_GE(ep.eigenvalues().minCoeff(), -1e-10 * scale);
    EXPECT_LE((ep.eigenvalues() - er.eigenvalues().cwiseMax(0.0)).norm(), 1e-9 * scale);
    indefinite += er.eigenvalues().minCoeff() < -1e-8 * scale;
  }
  EXPECT_GE(indefinite, 10) << "some barrier Hessians are indefinite (the projection matters)";
}

}  // namespace
}  // namespace snh::contact
