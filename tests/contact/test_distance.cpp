// The distances: every piece's gradient and Hessian by finite differences at random configurations of each
// type and at degenerate ones; the classification against a brute-force distance on thousands of random
// configurations; continuity (and C¹ where the pieces meet) across type boundaries.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "fd_check.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_edge_distance.hpp"
#include "snh/contact/point_point_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {
namespace {

using test::expect_derivatives;
using test::random_point;
using P2 = std::array<Vec3, 2>;
using P3 = std::array<Vec3, 3>;
using P4 = std::array<Vec3, 4>;

// Brute-force references, written independently of the library's region tests: the distance to a
// segment by clamping the projection parameter, to a triangle as the least of its plane (when the
// projection's barycentric coordinates are all ≥ 0) and its three edges, between segments as the least of
// the four endpoint-to-segment distances and the interior line–line minimiser (when inside both).
double segment_ref(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 v = b - a;
  const double s = std::clamp((p - a).dot(v) / v.squaredNorm(), 0.0, 1.0);
  return (p - (a + s * v)).squaredNorm();
}
double triangle_ref(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  double best = std::min({segment_ref(p, t0, t1), segment_ref(p, t1, t2), segment_ref(p, t2, t0)});
  // Solve the 2×2 normal equations for p ≈ t0 + β e1 + γ e2.
  const Vec3 e1 = t1 - t0, e2 = t2 - t0, r = p - t0;
  Eigen::Matrix2d G;
  G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
  const Eigen::Vector2d bg = G.ldlt().solve(Eigen::Vector2d(e1.dot(r), e2.dot(r)));
  if (bg[0] >= 0 && bg[1] >= 0 && bg[0] + bg[1] <= 1)
    best = std::min(best, (r - bg[0] * e1 - bg[1] * e2).squaredNorm());
  return best;
}
double segments_ref(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  double best = std::min(
      {segment_ref(a0, b0, b1), segment_ref(a1, b0, b1), segment_ref(b0, a0, a1), segment_ref(b1, a0, a1)});
  const Vec3 a = a1 - a0, b = b1 - b0, r = b0 - a0;
  Eigen::Matrix2d G;
  G << a.dot(a), -a.dot(b), -a.dot(b), b.dot(b);
  if (std::abs(G.determinant()) > 1e-14 * G.norm() * G.norm()) {
    const Eigen::Vector2d st = G.inverse() * Eigen::Vector2d(a.dot(r), -b.dot(r));
    if (st[0] > 0 && st[0] < 1 && st[1] > 0 && st[1] < 1)
      best = std::min(best, (r + st[1] * b - st[0] * a).squaredNorm());
  }
  return best;
}

auto pt_derivs(PointTriangleType type) {
  return [type](const P4& x) { return point_triangle_distance_derivatives(x[0], x[1], x[2], x[3], type); };
}
auto ee_derivs(EdgeEdgeType type) {
  return [type](const P4& x) { return edge_edge_distance_derivatives(x[0], x[1], x[2], x[3], type); };
}
auto pe_derivs(PointEdgeType type) {
  return [type](const P3& x) { return point_edge_distance_derivatives(x[0], x[1], x[2], type); };
}

TEST(Distance, PointPointDerivatives) {
  std::mt19937_64 rng(1);
  for (int i = 0; i < 20; ++i) {
    const P2 x = {random_point(rng), random_point(rng)};
    expect_derivatives([](const P2& y) { return point_point_distance_derivatives(y[0], y[1]); }, x, "point-point");
    EXPECT_DOUBLE_EQ(point_point_distance_derivatives(x[0], x[1]).value, point_point_distance(x[0], x[1]));
  }
}

TEST(Distance, PointEdgeEveryTypeAtRandom) {
  std::mt19937_64 rng(2);
  std::map<PointEdgeType, int> seen;
  for (int i = 0; i < 150; ++i) {
    const P3 x = {random_point(rng, -2, 2), random_point(rng), random_point(rng)};
    const PointEdgeType type = point_edge_distance_type(x[0], x[1], x[2]);
    ++seen[type];
    expect_derivatives(pe_derivs(type), x, std::string("point-edge ") + std::string(to_string(type)));
    const double d = point_edge_distance(x[0], x[1], x[2]);
    EXPECT_NEAR(d, segment_ref(x[0], x[1], x[2]), 1e-12 * (1 + d));
    EXPECT_NEAR(point_edge_distance_derivatives(x[0], x[1], x[2]).value, d, 1e-12 * (1 + d));
  }
  EXPECT_EQ(seen.size(), 3u);
}

TEST(Distance, PointTriangleEveryTypeAtRandom) {
  std::mt19937_64 rng(3);
  std::map<PointTriangleType, int> seen;
  for (int i = 0; i < 300; ++i) {
    const P4 x = {random_point(rng, -2, 2), random_point(rng), random_point(rng), random_point(rng)};
    const PointTriangleType type = point_triangle_distance_type(x[0], x[1], x[2], x[3]);
    ++seen[type];
    expect_derivatives(pt_derivs(type), x, std::string("point-triangle ") + std::string(to_string(type)));
    EXPECT_NEAR(point_triangle_distance_derivatives(x[0], x[1], x[2], x[3]).value,
                point_triangle_distance(x[0], x[1], x[2], x[3]), 1e-12);
  }
  EXPECT_EQ(seen.size(), 7u) << "every point-triangle type met";
  for (const auto& [type, n] : seen) EXPECT_GE(n, 5) << to_string(type);
}

TEST(Distance, EdgeEdgeEveryTypeAtRandom) {
  std::mt19937_64 rng(4);
  std::map<EdgeEdgeType, int> seen;
  for (int i = 0; i < 400; ++i) {
    const P4 x = {random_point(rng), random_point(rng), random_point(rng), random_point(rng)};
    const EdgeEdgeType type = edge_edge_distance_type(x[0], x[1], x[2], x[3]);
    ++seen[type];
    expect_derivatives(ee_derivs(type), x, std::string("edge-edge ") + std::string(to_string(type)));
    EXPECT_NEAR(edge_edge_distance_derivatives(x[0], x[1], x[2], x[3]).value,
                edge_edge_distance(x[0], x[1], x[2], x[3]), 1e-12);
  }
  EXPECT_EQ(seen.size(), 9u) << "every edge-edge type met";
  for (const auto& [type, n] : seen) EXPECT_GE(n, 5) << to_string(type);
}

/// The classified distance equals the brute-force one (relative to the configuration's scale).
TEST(Distance, ClassificationAgreesWithBruteForce) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> scale_exp(-3, 3);
  for (int i = 0; i < 5000; ++i) {
    const double s = std::pow(10.0, scale_exp(rng));  // scale invariance: sizes from 1e-3 to 1e3
    const P4 x = {s * random_point(rng, -2, 2), s * random_point(rng), s * random_point(rng), s * random_point(rng)};
    const double pt = point_triangle_distance(x[0], x[1], x[2], x[3]);
    EXPECT_NEAR(pt, triangle_ref(x[0], x[1], x[2], x[3]), 1e-11 * s * s) << "point-triangle, sample " << i;
    const double ee = edge_edge_distance(x[0], x[1], x[2], x[3]);
    EXPECT_NEAR(ee, segments_ref(x[0], x[1], x[2], x[3]), 1e-11 * s * s) << "edge-edge, sample " << i;
  }
}

/// The distance is never larger than the distance of any sampled pair of points on the two primitives
/// (a reference that knows nothing of features), and comes within the sampling's resolution of the least.
TEST(Distance, NoSampledPairIsCloser) {
  std::mt19937_64 rng(6);
  constexpr int n = 40;
  for (int i = 0; i < 200; ++i) {
    const P4 x = {random_point(rng, -2, 2), random_point(rng), random_point(rng), random_point(rng)};
    double pt_min = 1e300, ee_min = 1e300;
    for (int a = 0; a <= n; ++a)
      for (int b = 0; b <= n; ++b) {
        const double u = double(a) / n, v = double(b) / n;
        if (u + v <= 1) pt_min = std::min(pt_min, (x[0] - (x[1] + u * (x[2] - x[1]) + v * (x[3] - x[1]))).squaredNorm());
        ee_min = std::min(ee_min, ((x[0] + u * (x[1] - x[0])) - (x[2] + v * (x[3] - x[2]))).squaredNorm());
      }
    const double pt = point_triangle_distance(x[0], x[1], x[2], x[3]);
    const double ee = edge_edge_distance(x[0], x[1], x[2], x[3]);
    EXPECT_LE(pt, pt_min + 1e-12);
    EXPECT_LE(ee, ee_min + 1e-12);
    // The grid spacing is ≤ 4/n in each coordinate's direction; the true minimiser is that close to a sample.
    EXPECT_GE(std::sqrt(pt), std::sqrt(pt_min) - 4.0 * 2.0 / n);
    EXPECT_GE(std::sqrt(ee), std::sqrt(ee_min) - 4.0 * 2.0 / n);
  }
}

/// The unsigned distance from a moving point (or a translated segment) changes no faster than the motion:
/// 1-Lipschitz, across every type boundary the path crosses.
TEST(Distance, ContinuousAcrossTypeBoundaries) {
  std::mt19937_64 rng(7);
  int changes = 0;
  for (int i = 0; i < 40; ++i) {
    const P4 x = {random_point(rng, -2, 2), random_point(rng), random_point(rng), random_point(rng)};
    const Vec3 dir = random_point(rng, -3, 3);
    constexpr int steps = 2000;
    double prev_pt = std::sqrt(point_triangle_distance(x[0], x[1], x[2], x[3]));
    double prev_ee = std::sqrt(edge_edge_distance(x[0], x[1], x[2], x[3]));
    auto prev_ptt = point_triangle_distance_type(x[0], x[1], x[2], x[3]);
    auto prev_eet = edge_edge_distance_type(x[0], x[1], x[2], x[3]);
    for (int k = 1; k <= steps; ++k) {
      const Vec3 shift = dir * (double(k) / steps);
      const Vec3 p = x[0] + shift, b0 = x[2] + shift, b1 = x[3] + shift;
      const double pt = std::sqrt(point_triangle_distance(p, x[1], x[2], x[3]));
      const double ee = std::sqrt(edge_edge_distance(x[0], x[1], b0, b1));
      const double moved = dir.norm() / steps;
      EXPECT_LE(std::abs(pt - prev_pt), moved * (1 + 1e-9) + 1e-12);
      EXPECT_LE(std::abs(ee - prev_ee), moved * (1 + 1e-9) + 1e-12);
      const auto ptt = point_triangle_distance_type(p, x[1], x[2], x[3]);
      const auto eet = edge_edge_distance_type(x[0], x[1], b0, b1);
      changes += (ptt != prev_ptt) + (eet != prev_eet);
      prev_pt = pt, prev_ee = ee, prev_ptt = ptt, prev_eet = eet;
    }
  }
  EXPECT_GE(changes, 80) << "the paths cross type boundaries";
}

/// At a configuration on the boundary of several types, each piece's derivatives are right and the pieces
/// agree in value and (if c1) in gradient: the full distance is C¹ there.
template <class Derivs, class Type>
void expect_pieces_meet(const P4& x, const std::vector<Type>& types, Derivs&& derivs, const std::string& where,
                        bool c1 = true) {
  const auto first = derivs(types[0])(x);
  for (Type t : types) {
    const std::string w = where + " piece " + std::string(to_string(t));
    expect_derivatives(derivs(t), x, w);
    const auto D = derivs(t)(x);
    EXPECT_NEAR(D.value, first.value, 1e-12 * (1 + first.value)) << w;
    if (c1) {
      EXPECT_LE((D.gradient - first.gradient).norm(), 1e-9 * (1 + first.gradient.norm())) << w;
    }
  }
}

TEST(Distance, VertexOverATriangleEdge) {
  using T = PointTriangleType;
  const Vec3 t0(0, 0, 0), t1(1, 0, 0), t2(0.2, 0.9, 0);
  for (double h : {0.3, 1e-4}) {
    const P4 x = {Vec3(0.4, 0, h), t0, t1, t2};  // above the edge t0–t1
    const T type = point_triangle_distance_type(x[0], t0, t1, t2);
    EXPECT_TRUE(type == T::p_e0 || type == T::p_t) << to_string(type);
    EXPECT_NEAR(point_triangle_distance(x[0], t0, t1, t2), h * h, 1e-15);
    expect_pieces_meet(x, std::vector<T>{T::p_e0, T::p_t}, pt_derivs, "vertex over edge h=" + std::to_string(h));
  }
}

TEST(Distance, VertexOverATriangleVertex) {
  using T = PointTriangleType;
  const Vec3 t0(0, 0, 0), t1(1, 0, 0), t2(0.2, 0.9, 0);
  for (double h : {0.5, 1e-4}) {
    const P4 x = {Vec3(0, 0, h), t0, t1, t2};  // above t0
    EXPECT_NEAR(point_triangle_distance(x[0], t0, t1, t2), h * h, 1e-15);
    expect_pieces_meet(x, std::vector<T>{T::p_t0, T::p_e0, T::p_e2, T::p_t}, pt_derivs,
                       "vertex over vertex h=" + std::to_string(h));
  }
}

TEST(Distance, ParallelEdges) {
  using T = EdgeEdgeType;
  // Parallel, overlapping along their length, 0.5 apart; and exactly collinear-direction but offset.
  const P4 x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 0.5, 0), Vec3(1.4, 0.5, 0)};
  const T type = edge_edge_distance_type(x[0], x[1], x[2], x[3]);
  EXPECT_NE(type, T::ea_eb) << "parallel segments never use the line-line piece";
  EXPECT_NEAR(edge_edge_distance(x[0], x[1], x[2], x[3]), 0.25, 1e-15);
  // Two endpoint-against-line pieces give the same distance but different gradients (rotating one edge
  // moves the distance differently): the kink the mollifier smooths away.
  expect_pieces_meet(x, std::vector<T>{T::ea1_eb, T::ea_eb0}, ee_derivs, "parallel", false);
  // Parallel and disjoint along their direction: endpoint against endpoint.
  const P4 y = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1.5, 0.5, 0), Vec3(2.5, 0.5, 0)};
  EXPECT_EQ(edge_edge_distance_type(y[0], y[1], y[2], y[3]), T::ea1_eb0);
  EXPECT_NEAR(edge_edge_distance(y[0], y[1], y[2], y[3]), 0.5, 1e-15);
  expect_derivatives(ee_derivs(T::ea1_eb0), y, "parallel disjoint");
  // Anti-parallel and a zero-length edge also avoid the line-line piece.
  const P4 z = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1.4, 0.5, 0), Vec3(0.3, 0.5, 0)};
  EXPECT_NE(edge_edge_distance_type(z[0], z[1], z[2], z[3]), T::ea_eb);
  const P4 w = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, 0.5, 0.1), Vec3(0.5, 0.5, 0.1)};
  EXPECT_EQ(edge_edge_distance_type(w[0], w[1], w[2], w[3]), T::ea_eb0);
  EXPECT_NEAR(edge_edge_distance(w[0], w[1], w[2], w[3]), 0.26, 1e-15);
}

TEST(Distance, NearlyParallelEdges) {
  using T = EdgeEdgeType;
  // Edge b turned by 1e-3 rad from a (within the mollifier's range): the line-line piece is still exact.
  for (double angle : {1e-2, 1e-3}) {
    const P4 x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.2, 0.3, 0.5),
                  Vec3(0.2 + std::cos(angle), 0.3, 0.5 + std::sin(angle))};
    const T type = edge_edge_distance_type(x[0], x[1], x[2], x[3]);
    EXPECT_NEAR(edge_edge_distance(x[0], x[1], x[2], x[3]), segments_ref(x[0], x[1], x[2], x[3]), 1e-12);
    expect_derivatives(ee_derivs(type), x, "nearly parallel " + std::string(to_string(type)), 1e-5);
    expect_derivatives(ee_derivs(T::ea_eb), x, "nearly parallel, line-line piece", 1e-5);
  }
}

TEST(Distance, EdgesMeetingNearTheirEndpoints) {
  using T = EdgeEdgeType;
  // a ends where b begins, b perpendicular to a and lifted by h: ea1–eb0 is the closest pair, at the corner
  // of four types.
  for (double h : {0.2, 1e-5}) {
    const P4 x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, h), Vec3(1, 1, h)};
    EXPECT_NEAR(edge_edge_distance(x[0], x[1], x[2], x[3]), h * h, 1e-15);
    expect_pieces_meet(x, std::vector<T>{T::ea1_eb0, T::ea_eb0, T::ea1_eb, T::ea_eb}, ee_derivs,
                       "edges meeting h=" + std::to_string(h));
  }
  // Crossing exactly (distance 0): the pieces are finite and their gradient vanishes.
  const P4 y = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0)};
  const auto D = edge_edge_distance_derivatives(y[0], y[1], y[2], y[3]);
  EXPECT_EQ(D.value, 0.0);
  EXPECT_TRUE(D.gradient.isZero() && D.hessian.allFinite());
}

TEST(Distance, DegenerateTriangleUsesItsEdges) {
  // A triangle whose three vertices are collinear: the distance is that to the nearest of its edges.
  const Vec3 t0(0, 0, 0), t1(1, 0, 0), t2(2, 0, 0), p(0.5, 0.3, 0.4);
  const auto type = point_triangle_distance_type(p, t0, t1, t2);
  EXPECT_NE(type, PointTriangleType::p_t);
  EXPECT_NEAR(point_triangle_distance(p, t0, t1, t2), 0.25, 1e-15);
}

}  // namespace
}  // namespace snh::contact
