// Signed distances to a surface (surface_distance.hpp): the size against a brute-force minimum over every
// triangle (IPC's point–triangle distance, written apart), the sign inside and outside a closed sphere with a
// UV seam and on both sides of an open sheet, zero on the surface itself, and one-line refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "snh/contact/point_triangle_distance.hpp"
#include "snh/contact/surface_distance.hpp"

namespace snh::contact {
namespace {

struct Surface {
  Eigen::Matrix3Xd v;
  Eigen::Matrix3Xi t;
};

/// A unit UV sphere, its triangles counter-clockwise from outside, with the seam at longitude 0 = 2π held by
/// two copies of each vertex on it (as a model's texture seam does).
Surface uv_sphere(int rings, int segments) {
  Surface s;
  s.v.resize(3, (rings + 1) * (segments + 1));
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      const double th = std::numbers::pi * i / rings, ph = 2 * std::numbers::pi * (j == segments ? 0 : j) / segments;
      s.v.col(i * (segments + 1) + j) << std::sin(th) * std::cos(ph), std::cos(th), -std::sin(th) * std::sin(ph);
    }
  std::vector<Eigen::Vector3i> tris;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * (segments + 1) + j, b = a + 1, c = a + segments + 1, d = c + 1;
      if (i > 0) tris.emplace_back(a, c, b);
      if (i + 1 < rings) tris.emplace_back(b, c, d);
    }
  s.t.resize(3, static_cast<Eigen::Index>(tris.size()));
  for (std::size_t k = 0; k < tris.size(); ++k) s.t.col(static_cast<Eigen::Index>(k)) = tris[k];
  return s;
}

double brute_force(const Surface& s, const Vec3& p) {
  double best = INFINITY;
  for (Eigen::Index f = 0; f < s.t.cols(); ++f)
    best = std::min(best, point_triangle_distance(p, s.v.col(s.t(0, f)), s.v.col(s.t(1, f)), s.v.col(s.t(2, f))));
  return std::sqrt(best);
}

TEST(SurfaceDistance, MatchesTheNearestTriangleAndKnowsInsideFromOutside) {
  const Surface s = uv_sphere(12, 24);
  const SurfaceDistance d(s.v, s.t);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> radius(0.3, 1.7);
  int inside = 0, outside = 0;
  for (int k = 0; k < 400; ++k) {
    Vec3 dir(g(rng), g(rng), g(rng));
    if (k < 40) dir = Vec3(1.0, 0.05 * g(rng), 0.02 * g(rng));  // at the seam (longitude 0)
    const double r = radius(rng);
    if (std::abs(r - 1.0) < 0.05) continue;  // the polygon lies within 5 % of the unit sphere
    const Vec3 p = r * dir.normalized();
    const double expected = brute_force(s, p);
    // Bounds: a vertex's distance, and a loose one far beyond it.
    const double got = d.signed_distance(p, Eigen::Index{k % s.v.cols()});
    const double loose = d.signed_distance(p, 10.0);
    EXPECT_NEAR(std::abs(got), expected, 1e-12 * (1 + expected)) << "point " << k;
    EXPECT_EQ(got, loose) << "point " << k;
    EXPECT_EQ(got > 0, r > 1.0) << "point " << k << " at radius " << r;
    (r > 1.0 ? outside : inside)++;
  }
  EXPECT_GT(inside, 50);
  EXPECT_GT(outside, 50);
}

TEST(SurfaceDistance, IsZeroOnTheSurfaceAndSignedAcrossAnOpenSheet) {
  // A 4×4 sheet in z = 0, counter-clockwise seen from +z.
  Surface s;
  s.v.resize(3, 25);
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 5; ++j) s.v.col(5 * i + j) << j, i, 0;
  s.t.resize(3, 32);
  for (int i = 0, f = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const int a = 5 * i + j;
      s.t.col(f++) << a, a + 1, a + 6;
      s.t.col(f++) << a, a + 6, a + 5;
    }
  const SurfaceDistance d(s.v, s.t);
  for (Eigen::Index v = 0; v < s.v.cols(); ++v) EXPECT_EQ(d.signed_distance(s.v.col(v), v), 0.0);
  EXPECT_EQ(d.signed_distance(Vec3(1.3, 2.6, 0.0), Eigen::Index{0}), 0.0);
  EXPECT_NEAR(d.signed_distance(Vec3(1.3, 2.6, 0.3), Eigen::Index{0}), 0.3, 1e-15);
  EXPECT_NEAR(d.signed_distance(Vec3(1.3, 2.6, -0.2), Eigen::Index{24}), -0.2, 1e-15);
  // Past the sheet's edge: the distance to that edge.
  EXPECT_NEAR(d.signed_distance(Vec3(7.0, 2.0, 4.0), Eigen::Index{0}), 5.0, 1e-12);
  EXPECT_TRUE(std::isnan(d.signed_distance(Vec3(1.0, 1.0, 1.0), 0.5)));  // a bound that is not one
}

TEST(SurfaceDistance, NearestPointsOfTrianglesIncludingOnesWithoutArea) {
  const Vec3 a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  EXPECT_TRUE(nearest_on_triangle(Vec3(0.5, 0.5, 3), a, b, c).isApprox(Vec3(0.5, 0.25, 0.25)));
  EXPECT_TRUE(nearest_on_triangle(Vec3(-1, -1, 0), a, b, c).isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE(nearest_on_triangle(Vec3(3, 1, 0), a, b, c).isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(nearest_on_triangle(Vec3(1, -1, 1), a, b, c).isApprox(Vec3(0.5, 0.5, 0)));
  EXPECT_TRUE(nearest_on_triangle(Vec3(2, 2, 0), a, b, c).isApprox(Vec3(0, 0.5, 0.5)));
  // Three points on a line: the nearest point of the segment they span.
  const Vec3 w = nearest_on_triangle(Vec3(1.5, 1, 0), a, Vec3(1, 0, 0), b);
  EXPECT_NEAR(w.sum(), 1.0, 1e-15);
  EXPECT_TRUE((w[0] * a + w[1] * Vec3(1, 0, 0) + w[2] * b).isApprox(Vec3(1.5, 0, 0)));
  EXPECT_TRUE(nearest_on_triangle(Vec3(5, 5, 5), a, a, a).isApprox(Vec3(1, 0, 0)));
}

TEST(SurfaceDistance, RefusesSurfacesItCannotMeasure) {
  const Surface s = uv_sphere(4, 6);
  EXPECT_THROW(SurfaceDistance(s.v, Eigen::Matrix3Xi(3, 0)), std::invalid_argument);
  Eigen::Matrix3Xi bad = s.t;
  bad(1, 3) = static_cast<int>(s.v.cols());
  EXPECT_THROW(SurfaceDistance(s.v, bad), std::invalid_argument);
  Eigen::Matrix3Xd nan = s.v;
  nan(2, 5) = NAN;
  EXPECT_THROW(SurfaceDistance(nan, s.t), std::invalid_argument);
  const SurfaceDistance d(s.v, s.t);
  EXPECT_THROW((void)d.signed_distance(Vec3::Zero(), Eigen::Index{-1}), std::invalid_argument);
  EXPECT_TRUE(std::isnan(d.signed_distance(Vec3(NAN, 0, 0), 1.0)));
}

}  // namespace
}  // namespace snh::contact
