// Continuous collision detection: hard cases (touching exactly at the end of the step, parallel motion,
// grazing, a vertex through a triangle's interior, edge or corner, zero and huge motion) and random trials
// against a certified reference: the returned t is never 0 for a separated start, never past the first
// contact, keeps the promised fraction of the starting distance, and is 1 when the step stays far.
#include <gtest/gtest.h>

#include <functional>
#include <limits>
#include <random>

#include "fd_check.hpp"
#include "snh/contact/ccd.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {
namespace {

using P4 = std::array<Vec3, 4>;
constexpr double kNever = std::numeric_limits<double>::infinity();

/// A step: four points, their displacements, and which primitive pair they form.
struct Step {
  P4 x, dx;
  bool edges = false;  ///< edge–edge (points 0–1 against 2–3) rather than point 0 against triangle 1–3

  double distance(double t) const {
    P4 y;
    for (int i = 0; i < 4; ++i) y[i] = x[i] + t * dx[i];
    return std::sqrt(edges ? edge_edge_distance(y[0], y[1], y[2], y[3])
                           : point_triangle_distance(y[0], y[1], y[2], y[3]));
  }
  double ccd(const CcdOptions& options = {}) const {
    return edges ? edge_edge_ccd(x[0], x[1], x[2], x[3], dx[0], dx[1], dx[2], dx[3], options)
                 : point_triangle_ccd(x[0], x[1], x[2], x[3], dx[0], dx[1], dx[2], dx[3], options);
  }
  /// A bound on |d distance / dt|: the largest relative speed of any two points (independent of the
  /// library's bound, coarser).
  double speed() const {
    double s = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) s = std::max(s, (dx[i] - dx[j]).norm());
    return s;
  }
};

/// The first time in [a, b] at which the distance is ≤ tol, or kNever: an interval is certified free when
/// (d(a) + d(b) − L (b − a)) / 2 > tol (the distance is L-Lipschitz in t); otherwise it is halved, down
/// to a width of 2⁻⁴⁰, where its start is returned.
double first_touch(const Step& s, double L, double a, double b, double da, double db, double tol, int depth) {
  if (da <= tol) return a;
  if ((da + db - L * (b - a)) / 2 > tol) return kNever;
  if (depth == 0) return a;
  const double m = 0.5 * (a + b), dm = s.distance(m);
  const double left = first_touch(s, L, a, m, da, dm, tol, depth - 1);
  return left != kNever ? left : first_touch(s, L, m, b, dm, db, tol, depth - 1);
}
double first_touch(const Step& s, double tol = 1e-12) {
  constexpr int n = 256;
  const double L = s.speed();
  for (int k = 0; k < n; ++k) {
    const double a = double(k) / n, b = double(k + 1) / n;
    const double t = first_touch(s, L, a, b, s.distance(a), s.distance(b), tol, 32);
    if (t != kNever) return t;
  }
  return kNever;
}
/// A certified lower bound on the distance over the whole step (from 4096 samples).
double min_distance_bound(const Step& s) {
  constexpr int n = 4096;
  double lo = kNever;
  for (int k = 0; k < n; ++k) lo = std::min(lo, (s.distance(double(k) / n) + s.distance(double(k + 1) / n) - s.speed() / n) / 2);
  return lo;
}

/// The contract for one step: t ∈ [0, 1]; t > 0 when separated at the start; no contact in [0, t]; the
/// distance at t at least keep·d₀ (below 1) and positive.
void expect_safe(const Step& s, const std::string& where, double keep = 0.1) {
  const double t = s.ccd({keep, 1'000'000});
  const double d0 = s.distance(0);
  ASSERT_GT(d0, 0.0) << where;
  EXPECT_GT(t, 0.0) << where;
  EXPECT_LE(t, 1.0) << where;
  const double touch = first_touch(s);
  if (touch != kNever) {
    EXPECT_LT(t, touch) << where << ": contact at " << touch;
  }
  EXPECT_GT(s.distance(t), 0.0) << where;
  if (t < 1.0) {
    EXPECT_GE(s.distance(t), keep * d0 * (1 - 1e-9)) << where;
  }
}

Step point_triangle(const Vec3& p, const Vec3& dp, const Vec3& dt = Vec3::Zero()) {
  return {{p, Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, {dp, dt, dt, dt}, false};
}

TEST(Ccd, VertexThroughInteriorEdgeAndCorner) {
  for (const Vec3& target : {Vec3(0.25, 0.25, 0), Vec3(0.5, 0, 0), Vec3(0.5, 0.5, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)}) {
    // Straight down from height 1 to 1 below the plane: contact at t = 0.5.
    const Step s = point_triangle(target + Vec3(0, 0, 1), Vec3(0, 0, -2));
    const double t = s.ccd();
    EXPECT_LT(t, 0.5);
    EXPECT_GT(t, 0.4) << "not overly conservative: at t the distance is ~10% of the start's";
    expect_safe(s, "through " + std::to_string(target.x()) + "," + std::to_string(target.y()));
  }
  // Oblique, and with the triangle moving up to meet the point.
  expect_safe(point_triangle(Vec3(-0.5, 0.3, 0.7), Vec3(1.0, 0.1, -1.5), Vec3(0, 0, 0.3)), "oblique");
}

TEST(Ccd, TouchingExactlyAtTheEndOfTheStep) {
  const Step s = point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1));  // reaches the plane at t = 1
  const double t = s.ccd();
  EXPECT_LT(t, 1.0);
  EXPECT_GT(t, 0.85);
  expect_safe(s, "touch at end");
  // Edges crossing exactly at t = 1.
  const Step e{{Vec3(0, 0, 1), Vec3(1, 0, 1), Vec3(0.5, -0.5, 0), Vec3(0.5, 0.5, 0)},
               {Vec3(0, 0, -1), Vec3(0, 0, -1), Vec3::Zero(), Vec3::Zero()}, true};
  EXPECT_LT(e.ccd(), 1.0);
  expect_safe(e, "edges touch at end");
}

TEST(Ccd, ParallelMotion) {
  // Edges sliding along each other 0.01 apart, overlapping all the step: the distance never changes, so
  // the whole step is free.
  const Step slide{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(-0.5, 0.01, 0), Vec3(0.5, 0.01, 0)},
                   {Vec3::Zero(), Vec3::Zero(), Vec3(1, 0, 0), Vec3(1, 0, 0)}, true};
  EXPECT_EQ(slide.ccd(), 1.0);
  // Sliding in from far along the same line: the distance falls from 1 to 0.01, below the kept tenth,
  // so the step stops before the overlap begins.
  const Step slide_in{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(-2, 0.01, 0), Vec3(-1, 0.01, 0)},
                      {Vec3::Zero(), Vec3::Zero(), Vec3(3, 0, 0), Vec3(3, 0, 0)}, true};
  EXPECT_LT(slide_in.ccd(), 1.0 / 3.0);
  expect_safe(slide_in, "sliding in");
  // Parallel edges approaching each other (collision of the whole length at t = 0.5).
  const Step meet{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 1, 0), Vec3(1.3, 1, 0)},
                  {Vec3::Zero(), Vec3::Zero(), Vec3(0, -2, 0), Vec3(0, -2, 0)}, true};
  EXPECT_LT(meet.ccd(), 0.5);
  expect_safe(meet, "parallel edges meeting");
  // A point sliding parallel to a triangle's plane, just above it.
  const Step glide = point_triangle(Vec3(-1, 0.3, 1e-3), Vec3(3, 0, 0));
  EXPECT_GT(glide.ccd(), 0.0);
  expect_safe(glide, "gliding above the plane");
}

TEST(Ccd, Grazing) {
  // A point passing just above the edge t0–t1 (y = 0) from outside: distance 1e-6 at closest, no contact.
  const Step above = point_triangle(Vec3(0.5, -1, 1e-6), Vec3(0, 2, 0));
  expect_safe(Step{{Vec3(0.5, -1, 1), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
                   {Vec3(0, 1, -1 + 1e-6), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()}, false},
              "grazing over the edge");
  expect_safe(above, "sliding over the edge");
  // The same path 1e-6 lower: it enters the triangle through its edge (contact just past t = 0.5).
  const Step through{{Vec3(0.5, -1, 1), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
                     {Vec3(0, 2, -2 - 1e-6), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()}, false};
  EXPECT_LT(through.ccd(), 0.5);
  expect_safe(through, "just through the edge");
  // Edges grazing at their endpoints: b's endpoint passes 1e-7 from a's endpoint.
  const Step ends{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1e-7, 1), Vec3(1, 1, 1)},
                  {Vec3::Zero(), Vec3::Zero(), Vec3(0, 0, -2), Vec3(0, 0, -2)}, true};
  expect_safe(ends, "edges grazing at endpoints");
}

TEST(Ccd, ZeroAndHugeMotion) {
  const Step still = point_triangle(Vec3(0.2, 0.2, 1e-9), Vec3::Zero());
  EXPECT_EQ(still.ccd(), 1.0);
  // Everything moving together: no relative motion.
  EXPECT_EQ(point_triangle(Vec3(0.2, 0.2, 0.1), Vec3(5, 5, 5), Vec3(5, 5, 5)).ccd(), 1.0);
  // Touching at the start: no step is safe.
  EXPECT_EQ(point_triangle(Vec3(0.2, 0.2, 0), Vec3(0, 0, 1)).ccd(), 0.0);
  // Huge motion through the triangle and far away from it.
  const Step through = point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1e8));
  const double t = through.ccd();
  EXPECT_GT(t, 0.0);
  EXPECT_LT(t, 1e-8);
  expect_safe(through, "huge motion through");
  EXPECT_EQ(point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, 1e8)).ccd(), 1.0) << "huge motion away";
}

TEST(Ccd, IterationBoundGivesASafeTime) {
  const Step s = point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1));
  const double t = s.ccd({0.1, 2});
  EXPECT_GT(t, 0.0);
  EXPECT_LT(t, first_touch(s));
  EXPECT_GE(s.distance(t), 0.1 * (1 - 1e-12));  // the first advance's bound, up to rounding
}

TEST(Ccd, BadInputThrows) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)point_triangle(Vec3(0.2, 0.2, nan), Vec3(0, 0, -1)).ccd(), std::invalid_argument);
  EXPECT_THROW((void)point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, inf, -1)).ccd(), std::invalid_argument);
  EXPECT_THROW((void)point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1)).ccd({0.0, 10}), std::invalid_argument);
  EXPECT_THROW((void)point_triangle(Vec3(0.2, 0.2, 1), Vec3(0, 0, -1e308), Vec3(0, 0, 1e308)).ccd(),
               std::invalid_argument);
}

/// Random steps, many of them colliding: compared with the certified reference.
TEST(Ccd, RandomTrialsNeverMissNeverStall) {
  std::mt19937_64 rng(31);
  int contacts = 0, free_far = 0;
  for (int i = 0; i < 600; ++i) {
    const bool edges = i % 2 == 1;
    Step s{{test::random_point(rng), test::random_point(rng), test::random_point(rng), test::random_point(rng)},
           {}, edges};
    // The first point (or edge) heads towards the other primitive's centroid, overshooting it.
    const Vec3 centre = edges ? Vec3(0.5 * (s.x[2] + s.x[3])) : Vec3((s.x[1] + s.x[2] + s.x[3]) / 3.0);
    const Vec3 head = 2.0 * (centre - s.x[0]) + 0.5 * test::random_point(rng);
    for (int k = 0; k < 4; ++k) s.dx[k] = (k < (edges ? 2 : 1) ? head : Vec3::Zero()) + 0.3 * test::random_point(rng);
    if (!(s.distance(0) > 1e-3)) continue;
    const std::string where = std::string(edges ? "edge-edge" : "point-triangle") + " trial " + std::to_string(i);
    expect_safe(s, where);
    const double touch = first_touch(s);
    contacts += touch != kNever;
    if (touch == kNever && min_distance_bound(s) > 0.1 * s.distance(0) * 1.01) {
      ++free_far;
      EXPECT_EQ(s.ccd(), 1.0) << where << ": the step never comes within the kept fraction";
    }
  }
  EXPECT_GE(contacts, 100);
  EXPECT_GE(free_far, 50);
}

}  // namespace
}  // namespace snh::contact
