// Kinematic colliders (fem/collider_term.hpp) and moving contact in a Simulation: the shape and mesh
// terms' derivatives by finite differences (near a capsule's caps, a box's faces, edges and corners, and
// the vertex–triangle, triangle–vertex and edge–edge pairs of a mesh), their step bounds on random steps
// (never onto or past the surface), a cube dropped on a sphere and on a box (backward Euler) coming to
// rest above it, a cube pressed by a moving slab (quasi-static) that never passes into it (the step is
// split where the slab's sweep is not clear), and runs with colliders out of range bit-identical to runs
// without.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/fem/embedded_points.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/sim/simulation.hpp"
#include "contact/surface_checks.hpp"
#include "sim/face_pins.hpp"
#include "fem/problem_fd.hpp"
#include "fem/weighted_points.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using testing::identity_through_weights;


using Shape = ColliderShape::Kind;

using test::flatten;
using test::unflatten;

/// A similarity: rotation about a tilted axis, uniform scale 1.3, translation.
Eigen::Affine3d tilted_pose(double t) {
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  A.linear() = 1.3 * Eigen::AngleAxisd(0.4 + t, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  A.translation() = Vec3(0.3, -0.2, 0.5) + t * Vec3(0.1, 0.0, 0.0);
  return A;
}

std::vector<int> iota_ids(Eigen::Index n) {
  std::vector<int> ids(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(i);
  return ids;
}

std::string fmt_kind(const ColliderShape& s) {
  return s.kind == Shape::sphere ? "sphere" : s.kind == Shape::capsule ? "capsule" : s.kind == Shape::box ? "box" : "plane";
}

ColliderShape sphere() { return {Shape::sphere, Vec3(0.1, 0.2, -0.1), Vec3::Zero(), 0.7}; }
ColliderShape capsule() { return {Shape::capsule, Vec3(-0.5, 0, 0), Vec3(0.5, 0.2, 0), 0.3}; }
ColliderShape box() { return {Shape::box, Vec3(0, 0.1, 0), Vec3(0.4, 0.3, 0.6), 0.0}; }

/// Points at distance `d` outside the shape in its base frame (world positions through the pose), next to
/// the given base-frame points of the surface, in the given directions.
Eigen::Matrix3Xd near(const std::vector<std::pair<Vec3, Vec3>>& at, double d, const Eigen::Affine3d& pose) {
  Eigen::Matrix3Xd X(3, static_cast<Eigen::Index>(at.size()));
  for (std::size_t i = 0; i < at.size(); ++i) X.col(static_cast<Eigen::Index>(i)) = pose * (at[i].first + d * at[i].second.normalized());
  return X;
}

void expect_fd(ShapeColliderTerm& term, const Eigen::Matrix3Xd& X, const char* what) {
  const auto n = static_cast<Eigen::Index>(X.cols());
  Problem problem(DofMap(std::vector<std::uint8_t>(3 * n, 0)));
  problem.add(term);
  const Eigen::VectorXd x = flatten(X);
  ASSERT_GT(term.energy(x), 0.0) << what;
  ASSERT_TRUE(std::isfinite(term.energy(x))) << what;
  const FdErrors e = problem_fd_errors(problem, x);
  EXPECT_LE(e.gradient, 1e-6) << what;
  EXPECT_LE(e.hessian, 1e-6) << what;
  EXPECT_GE(hessian_min_eigenvalue_ratio(problem, x, PsdProjection::clamp), -1e-9) << what;
}

/// Places on a shape's surface (base frame) and outward directions there: the capsule's side, both caps (on
/// and off the axis), near where they meet; the box's faces, edges and corners.
std::vector<std::pair<Vec3, Vec3>> surface_probes(const ColliderShape& shape) {
  std::vector<std::pair<Vec3, Vec3>> at;
  if (shape.kind == Shape::sphere) {
    for (const Vec3& n : {Vec3(1, 0, 0), Vec3(0.3, -1, 0.2), Vec3(-1, 1, 1), Vec3(0, 0, -1), Vec3(2, 1, -1), Vec3(-1, -1, 0.5)})
      at.push_back({shape.a + shape.radius * n.normalized(), n});
  } else if (shape.kind == Shape::capsule) {
    const Vec3 axis = (shape.b - shape.a).normalized(), side = axis.cross(Vec3(0, 0, 1)).normalized();
    const Vec3 up(0, 0, 1);
    at = {{0.5 * (shape.a + shape.b) + 0.3 * side, side}, {shape.a - 0.3 * axis, -axis},
          {shape.b + 0.3 * (axis + up).normalized(), axis + up}, {shape.a + 0.3 * (up - 0.05 * axis).normalized(), up - 0.05 * axis},
          {shape.b + 0.3 * (side + 0.02 * axis).normalized(), side + 0.02 * axis}, {shape.a + 0.02 * (shape.b - shape.a) - 0.3 * up, -up}};
  } else {  // a face, two edges, two corners, a face near an edge
    const Vec3 h = shape.b, c = shape.a;
    at = {{c + Vec3(h[0], 0.1, 0.2), Vec3(1, 0, 0)},
          {c + Vec3(h[0], h[1], 0.1), Vec3(1, 1, 0)},
          {c + Vec3(-h[0], 0.05, -h[2]), Vec3(-1, 0, -2)},
          {c + Vec3(h[0], h[1], h[2]), Vec3(1, 2, 1)},
          {c + Vec3(-h[0], -h[1], h[2]), Vec3(-1, -1, 1)},
          {c + Vec3(0.1, -h[1], h[2] - 0.01), Vec3(0, -1, 0)}};
  }
  return at;
}

TEST(ShapeColliderTerm, MatchesFiniteDifferencesNearCapsEdgesAndCorners) {
  const double dhat = 0.1, d = 0.04;
  const Eigen::Affine3d pose = tilted_pose(0.7);
  for (const ColliderShape& shape : {sphere(), capsule(), box()}) {
    ShapeColliderTerm term(EmbeddedPoints::plain({0, 1, 2, 3, 4, 5}, "test"), shape, tilted_pose, dhat, 10.0);
    term.at_time(0.7);
    const std::vector<std::pair<Vec3, Vec3>> at = surface_probes(shape);
    // The capsule's caps and the box's edges and corners: the directions above point outward there.
    const Eigen::Matrix3Xd X = near(at, d, pose);
    for (Eigen::Index i = 0; i < X.cols(); ++i)
      EXPECT_NEAR(term.point_distance(flatten(X), static_cast<int>(i)), 1.3 * d, 1e-12) << "vertex " << i;
    expect_fd(term, X, shape.kind == Shape::sphere ? "sphere" : shape.kind == Shape::capsule ? "capsule" : "box");
  }
  // A moving plane: the signed distance, its derivatives, and +∞ behind it.
  ShapeColliderTerm plane(EmbeddedPoints::plain({0, 1}, "test"), {Shape::plane, Vec3(0, 0, 0), Vec3(0, 2, 0), 0.0}, tilted_pose, dhat, 10.0);
  plane.at_time(0.7);
  const Eigen::Matrix3Xd P = near({{Vec3(0.2, 0, 0.1), Vec3(0, 1, 0)}, {Vec3(-0.3, 0, 0.4), Vec3(0, 1, 0)}}, d, pose);
  expect_fd(plane, P, "plane");
  EXPECT_EQ(plane.energy(flatten(near({{Vec3(0.2, 0, 0.1), Vec3(0, 1, 0)}, {Vec3(0, 0, 0), Vec3(0, -1, 0)}}, d, pose))), INFINITY);
}

TEST(ShapeColliderTerm, MaxStepNeverReachesTheSurfaceOnRandomSteps) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int limited = 0;
  for (const ColliderShape& shape : {sphere(), capsule(), box()}) {
    ShapeColliderTerm term(EmbeddedPoints::plain({0}, "test"), shape, tilted_pose, 0.1, 1.0);
    term.at_time(0.3);
    for (int k = 0; k < 300; ++k) {
      Eigen::VectorXd x(3), dx(3);
      do {
        for (int i = 0; i < 3; ++i) x[i] = 2.0 * u(rng);
      } while (!(term.point_distance(x, 0) > 1e-3));
      for (int i = 0; i < 3; ++i) dx[i] = 3.0 * u(rng);
      const double d0 = term.point_distance(x, 0), alpha = term.max_step(x, dx);
      ASSERT_GT(alpha, 0.0);
      if (alpha < 1.0) ++limited;
      // Densely along the allowed part: never below a tenth of the start (up to rounding).
      for (int s = 0; s <= 400; ++s) {
        const Eigen::VectorXd y = x + (alpha * s / 400.0) * dx;
        ASSERT_GE(term.point_distance(y, 0), 0.1 * d0 * (1 - 1e-9)) << "step " << k << " at " << s;
      }
      // And not needlessly short: the path's first point below a tenth is close after alpha.
      if (alpha < 1.0) {
        double first = 1.0;
        for (int s = 0; s <= 2000; ++s)
          if (term.point_distance(x + (s / 2000.0) * dx, 0) < 0.1 * d0) {
            first = s / 2000.0;
            break;
          }
        EXPECT_GE(alpha, first - 1e-3) << "step " << k;
      }
    }
  }
  EXPECT_GT(limited, 40);  // many steps did run into the shapes
}

// ---- a crossing test of our own (orientation signs): does segment pq pass through triangle abc?

double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return (b - a).dot((c - a).cross(d - a)); }

bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0)) return false;
  const double s0 = orient(p, q, a, b), s1 = orient(p, q, b, c), s2 = orient(p, q, c, a);
  return !((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0));
}

/// Does an edge of one triangle set cross a triangle of the other?
bool surfaces_cross(const Eigen::Matrix3Xi& F, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& T, const Eigen::Matrix3Xd& W) {
  const auto edges_through = [](const Eigen::Matrix3Xi& A, const Eigen::Matrix3Xd& X, const Eigen::Matrix3Xi& B, const Eigen::Matrix3Xd& Y) {
    for (Eigen::Index i = 0; i < A.cols(); ++i)
      for (int e = 0; e < 3; ++e)
        for (Eigen::Index j = 0; j < B.cols(); ++j)
          if (segment_crosses_triangle(X.col(A(e, i)), X.col(A((e + 1) % 3, i)), Y.col(B(0, j)), Y.col(B(1, j)), Y.col(B(2, j))))
            return true;
    return false;
  };
  return edges_through(F, V, T, W) || edges_through(T, W, F, V);
}

/// One tet (simulated: X, its surface F) under a small tilted triangle pair (the collider: W, T): a tet vertex
/// under a collider triangle, a collider vertex over a tet face, and crossing edges close together.
struct TetUnderTriangles {
  Eigen::Matrix3Xd X{3, 4}, W{3, 4};
  Eigen::Matrix3Xi F{3, 4}, T{3, 2};
  TetUnderTriangles() {
    X << 0, 1, 0, 0.3,  //
        0, 0, 1, 0.3,    //
        0, 0, 0, 0.95;
    F << 0, 0, 1, 0, 2, 1, 2, 3, 1, 3, 3, 2;
    W << -0.2, 0.9, 0.1, 0.6,  //
        0.25, 0.2, 0.9, 0.7,    //
        1.0, 1.02, 0.99, 0.4;
    T << 0, 0, 1, 2, 2, 3;
  }
};

TEST(MeshColliderTerm, MatchesFiniteDifferencesWithEachPairKind) {
  const TetUnderTriangles fixture;
  const Eigen::Matrix3Xd& X = fixture.X;
  const Eigen::Matrix3Xi& F = fixture.F;
  const Eigen::Matrix3Xd& W = fixture.W;
  const Eigen::Matrix3Xi& T = fixture.T;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::Matrix3Xd Y = X;
    for (Eigen::Index i = 0; i < Y.size(); ++i) Y.data()[i] += u(rng);
    const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.01 * t)); };
    MeshColliderTerm term(F, EmbeddedPoints::every(X.cols()), X, W, T, pose, 0.3, 5.0);
    term.at_time(1.0);
    Problem problem(DofMap(std::vector<std::uint8_t>(12, 0)));
    problem.add(term);
    const Eigen::VectorXd x = flatten(Y);
    ASSERT_GT(term.energy(x), 0.0);
    ASSERT_TRUE(std::isfinite(term.energy(x)));
    const FdErrors e = problem_fd_errors(problem, x);
    EXPECT_LE(e.gradient, 1e-6) << "trial " << trial;
    EXPECT_LE(e.hessian, 1e-6) << "trial " << trial;
    Eigen::VectorXd g;
    HessianMatrix H;
    problem.evaluate(x, g, &H, PsdProjection::clamp);
    const Eigen::MatrixXd Hd = Eigen::MatrixXd(H.matrix).selfadjointView<Eigen::Lower>();
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hd).eigenvalues().minCoeff(), -1e-9 * Hd.norm());
  }
}

TEST(MeshColliderTerm, ATurnedScaledMovedColliderFindsWhatOneBuiltWhereItIsFinds) {
  // A fine plane (30 × 30 cells, 1 800 triangles) turned, tilted, scaled and moved by its pose to just above
  // a cube's top: its tree is searched in its base frame through the inverse pose. A still collider built
  // from the placed vertices finds the same candidates, distances and steps, bit for bit (not the same
  // energy: its rest is where it is placed, so its edges' mollifier thresholds are 1.3² times larger).
  const VolumeMesh m = box_tets(3);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const int n = 30;
  Eigen::Matrix3Xd W(3, (n + 1) * (n + 1));
  Eigen::Matrix3Xi T(3, 2 * n * n);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) W.col(j * (n + 1) + i) << -2.0 + 4.0 * i / n, 0.0, -2.0 + 4.0 * j / n;
  for (int j = 0, f = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      T.col(f++) << a, a + n + 2, a + 1;
      T.col(f++) << a, a + n + 1, a + n + 2;
    }
  const ColliderPose pose = [](double t) {
    return Eigen::Affine3d(Eigen::Translation3d(0.1 * t, 1.005, 0.0) * Eigen::AngleAxisd(0.7 * t, Vec3::UnitY()) *
                           Eigen::AngleAxisd(0.003, Vec3::UnitX()) * Eigen::Scaling(1.3));
  };
  const Eigen::VectorXd x = flatten(m.vertices);
  Eigen::VectorXd up = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) up[3 * v + 1] = 0.01 * (1.0 + m.vertices(1, v));
  MeshColliderTerm posed(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, W, T, pose, 0.02, 1.0);
  for (const double t : {0.0, 0.3, 1.0, 2.5}) {
    posed.at_time(t);
    const MeshColliderTerm still(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, posed.collider_vertices(), T, {}, 0.02, 1.0);
    EXPECT_GT(posed.active_pairs(x), 0) << "t " << t;
    EXPECT_EQ(posed.active_pairs(x), still.active_pairs(x)) << "t " << t;
    Stencil a, b;  // every candidate's simulated vertices, in order: the same candidates
    posed.stencil(x, a);
    still.stencil(x, b);
    EXPECT_EQ(a.vertices, b.vertices) << "t " << t;
    EXPECT_FALSE(a.vertices.empty());
    EXPECT_EQ(posed.min_distance(x), still.min_distance(x)) << "t " << t;
    EXPECT_EQ(posed.max_step(x, up), still.max_step(x, up)) << "t " << t;
    EXPECT_LT(posed.max_step(x, up), 1.0) << "t " << t;
  }
}

TEST(MeshColliderTerm, MaxStepAndSweepNeverCrossOnRandomSteps) {
  // A cube's surface against a slab: random steps of the cube (max_step) and random jumps of the slab
  // (sweep, the cube still); where the whole jump crosses, the bounded one does not, and the distance stays
  // positive.
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const Slab slab(Vec3(-2, 1.05, -2), Vec3(2, 1.25, 2));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int crossing = 0;
  for (int k = 0; k < 40; ++k) {
    const Vec3 jump(0.3 * u(rng), -0.6 - 0.8 * std::abs(u(rng)), 0.3 * u(rng));
    const ColliderPose pose = [jump](double t) { return Eigen::Affine3d(Eigen::Translation3d(t * jump)); };
    MeshColliderTerm term(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, slab.V, slab.T, pose, 0.02, 1.0);
    const Eigen::VectorXd x = flatten(m.vertices);
    // The slab's jump from t = 0 to 1.
    const double a = term.sweep(x, Eigen::VectorXd::Zero(x.size()), 0.0, 1.0);
    ASSERT_GT(a, 0.0);
    const Eigen::Matrix3Xd at_end = (slab.V.colwise() + jump);
    if (surfaces_cross(F, m.vertices, slab.T, at_end)) ++crossing;
    term.at_time(a);
    ASSERT_FALSE(surfaces_cross(F, m.vertices, slab.T, term.collider_vertices())) << "jump " << k;
    ASSERT_TRUE(std::isfinite(term.energy(x))) << "jump " << k;
    // The cube's random step towards the slab at rest.
    term.at_time(0.0);
    Eigen::VectorXd dx(x.size());
    for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = 0.05 * u(rng);
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v) dx[3 * v + 1] += 1.0 + 0.5 * std::abs(u(rng));
    const double b = term.max_step(x, dx);
    ASSERT_GT(b, 0.0);
    if (surfaces_cross(F, unflatten(x + dx), slab.T, slab.V)) ++crossing;
    ASSERT_FALSE(surfaces_cross(F, unflatten(x + b * dx), slab.T, slab.V)) << "step " << k;
    ASSERT_GT(term.min_distance(x + b * dx), 0.0);
  }
  EXPECT_GT(crossing, 40);  // most full jumps and steps do cross
}

// ---- simulations

/// The mesh's bottom layer (y = -1) as a kinematic set following these motions.
KinematicSet bottom_pins(const VolumeMesh& m, std::vector<Motion> motions) { return face_pins(m, 1, -1.0, std::move(motions), "bottom"); }

SimulationSetup cube_setup(const VolumeMesh& m, Integrator integrator) {
  SimulationSetup setup;
  setup.mesh = m;
  setup.materials = {make_material("stable_neo_hookean", {2e5, 2e6})};
  setup.density = 100.0;
  setup.integrator = integrator;
  setup.dt = 0.01;
  setup.newton.tolerance = 1e-2;
  setup.linear.name = "ldlt";
  return setup;
}

std::vector<int> surface_of(const VolumeMesh& m) {
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  std::vector<int> s(F.data(), F.data() + F.size());
  std::sort(s.begin(), s.end());
  s.erase(std::unique(s.begin(), s.end()), s.end());
  return s;
}

/// A cube [−1, 1]³ dropped under gravity from rest onto a shape below it; returns the distances.
void drop_onto(const ColliderShape& shape, const char* what) {
  const VolumeMesh m = box_tets(3);
  SimulationSetup setup = cube_setup(m, Integrator::backward_euler);
  setup.gravity = Vec3(0, -9.8, 0);
  setup.mass_damping = 2.0;
  const double dhat = 0.02;
  auto term = std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), shape, ColliderPose{}, dhat, 1e8);
  setup.terms.push_back(term);
  Simulation sim(std::move(setup));
  double lowest = INFINITY;
  for (int s = 1; s <= 120; ++s) {
    const StepReport r = sim.step(0.01 * s);
    ASSERT_TRUE(r.converged) << what << " step " << s << ": " << r.failure;
    const double d = term->min_distance(sim.x());
    ASSERT_GT(d, 0.0) << what << " step " << s;  // no vertex on or inside the shape
    lowest = std::min(lowest, d);
  }
  const double rest = term->min_distance(sim.x());
  EXPECT_LT(rest, dhat) << what;                          // resting on the barrier, not floating
  EXPECT_LT(sim.v().cwiseAbs().maxCoeff(), 0.05) << what;  // at rest
  EXPECT_GT(sim.x()(Eigen::seqN(1, m.vertex_count(), 3)).minCoeff(), shape.a[1]) << what;  // above it
  std::cout << what << ": lowest distance " << lowest << ", at rest " << rest << "\n";
}

TEST(ShapeColliderTerm, ACubeDroppedOnASphereAndOnABoxComesToRestAboveIt) {
  drop_onto({Shape::sphere, Vec3(0, -5.2, 0), Vec3::Zero(), 4.0}, "sphere");
  drop_onto({Shape::box, Vec3(0.3, -1.7, -0.2), Vec3(1.5, 0.5, 1.5), 0.0}, "box");
}

TEST(MeshColliderTerm, ASlabPressingACubeNeverPassesIntoIt) {
  // Quasi-static: a cube [−1, 1]³ held at its bottom face; a slab (a closed mesh) comes down from 0.03
  // above it by 0.5 over 10 steps, 0.05 a step, more than the gap it leaves (the barrier's). Checked at
  // every step: no cube vertex inside the slab, no cube edge through a slab triangle or slab edge through
  // a cube triangle. Without the splitting of the step in time the slab jumps past the cube's top
  // vertices (seen once by hand, with the split disabled).
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  SimulationSetup setup = cube_setup(m, Integrator::quasi_static);
  KinematicSet bottom = bottom_pins(m, {});
  setup.kinematic.push_back(bottom);
  const Slab slab(Vec3(-1.4, 1.03, -1.5), Vec3(1.6, 1.13, 1.5));
  const double speed = 0.5;  // per unit time; the run is t = 0.1 … 1
  const ColliderPose pose = [speed](double t) { return Eigen::Affine3d(Eigen::Translation3d(0, -speed * t, 0)); };
  const double dhat = 0.02;
  auto term = std::make_shared<MeshColliderTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, slab.V, slab.T, pose, dhat, 1e9);
  setup.terms.push_back(term);
  Simulation sim(std::move(setup));
  int splits = 0, iterations = 0;
  double closest = INFINITY;
  for (int s = 1; s <= 10; ++s) {
    const double t = 0.1 * s;
    const StepReport r = sim.step(t);
    ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
    splits += r.splits;
    iterations += r.newton.iterations;
    term->at_time(t);
    const Eigen::Matrix3Xd V = unflatten(sim.x());
    const double y_lo = slab.lo[1] - speed * t, y_hi = slab.hi[1] - speed * t;
    for (Eigen::Index v = 0; v < V.cols(); ++v)
      ASSERT_FALSE(V(1, v) >= y_lo && V(1, v) <= y_hi && V(0, v) >= slab.lo[0] && V(0, v) <= slab.hi[0] && std::abs(V(2, v)) <= 1.5)
          << "step " << s << ": vertex " << v << " inside the slab";
    ASSERT_FALSE(surfaces_cross(F, V, slab.T, term->collider_vertices())) << "step " << s;
    const double d = term->min_distance(sim.x());
    ASSERT_GT(d, 0.0) << "step " << s;
    closest = std::min(closest, d);
  }
  EXPECT_GT(splits, 0);
  // Pressed: the cube's top is now below where it started, under the slab.
  EXPECT_LT(sim.x()(Eigen::seqN(1, m.vertex_count(), 3)).maxCoeff(), 1.03 - 0.5);
  std::cout << "splits " << splits << ", Newton iterations " << iterations << ", closest " << closest << "\n";
}

TEST(ShapeColliderTerm, AMovingWallHitsACubeInSubStepsOfBackwardEuler) {
  // Backward Euler, no gravity: a wall (a box 1 thick) 0.1 from a cube at rest moves at 10 m/s, 0.1 a step
  // of h = 0.01, far more than the gap the barrier leaves: its whole step would carry the cube's face
  // vertices into it. The step is cut into sub-steps of a part of h, each clear of the wall's sweep against
  // the cube's inertial prediction; the cube is struck away. (At 20 m/s the sub-steps shrink below a
  // millionth of h and the step fails with its one line: docs/solvers.md, "Moving colliders within a run".)
  const VolumeMesh m = box_tets(3);
  SimulationSetup setup = cube_setup(m, Integrator::backward_euler);
  const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(-10.0 * t, 0, 0)); };
  auto wall = std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), ColliderShape{Shape::box, Vec3(1.6, 0, 0), Vec3(0.5, 3, 3), 0.0}, pose, 0.02, 1e8);
  setup.terms.push_back(wall);
  setup.newton.step_tolerance = 1e-9;  // as scenes do: forces reach m v / h' ~ 1e8 on the shortest sub-steps h'
  Simulation sim(std::move(setup));
  int splits = 0;
  for (int s = 1; s <= 20; ++s) {
    const StepReport r = sim.step(0.01 * s);
    ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
    splits += r.splits;
    ASSERT_NEAR(sim.time(), 0.01 * s, 1e-15);
    ASSERT_GT(wall->min_distance(sim.x()), 0.0) << "step " << s;  // at the wall's pose at the step's time
  }
  EXPECT_GT(splits, 0);
  EXPECT_LT(sim.v()(Eigen::seqN(0, m.vertex_count(), 3)).mean(), -10.0);  // struck: moving away faster than the wall
  EXPECT_EQ(sim.inertia().terms().dt, 0.01);                              // the time step restored
  std::cout << "splits " << splits << ", mean x velocity " << sim.v()(Eigen::seqN(0, m.vertex_count(), 3)).mean() << "\n";
}

/// Targets of a set: its rest positions translated by t·v.
class Translating final : public KinematicProvider {
 public:
  Translating(Eigen::Matrix3Xd rest, Vec3 v) : rest_(std::move(rest)), v_(std::move(v)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override { out = rest_.colwise() + t * v_; }

 private:
  Eigen::Matrix3Xd rest_;
  Vec3 v_;
};

TEST(ShapeColliderTerm, AQuasiStaticCarrierTakesTheFreeFleshAlongInTheStepsCheck) {
  // Quasi-static: a cube whose bottom layer is pinned and a sphere 0.2 from its −x face, all translated by
  // 0.5 a step along +x (a hand's bones and the capsule of another finger moving together). Checked with
  // the free vertices held still, the sphere runs into the face each step and every step is split; with a
  // carrier (the flesh-following frames of a flesh run: here the same translation) the free vertices are
  // taken along, the check is clear and no step is split. The sphere never reaches the cube.
  const Vec3 v(5.0, 0.0, 0.0);
  for (const bool carrier : {false, true}) {
    const VolumeMesh m = box_tets(2);
    SimulationSetup setup = cube_setup(m, Integrator::quasi_static);
    KinematicSet bottom;
    bottom.name = "bottom";
    for (Eigen::Index i = 0; i < m.vertex_count(); ++i)
      if (m.vertices(1, i) == -1.0) bottom.vertices.push_back(static_cast<int>(i));
    bottom.provider = std::make_shared<Translating>(m.vertices(Eigen::all, bottom.vertices), v);
    setup.kinematic = {bottom};
    if (carrier)
      setup.carrier = [v, n = m.vertex_count()](double t, std::vector<Eigen::Matrix<double, 3, 4>>& frames) {
        Eigen::Matrix<double, 3, 4> f;
        f << Mat3::Identity(), t * v;
        frames.assign(static_cast<std::size_t>(n), f);
      };
    const ColliderPose pose = [v](double t) { return Eigen::Affine3d(Eigen::Translation3d(t * v)); };
    auto sphere = std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), ColliderShape{Shape::sphere, Vec3(-1.5, 0, 0), Vec3::Zero(), 0.3}, pose, 0.05, 1e3);
    setup.terms.push_back(sphere);
    Simulation sim(std::move(setup));
    int splits = 0;
    for (int s = 1; s <= 5; ++s) {
      const StepReport r = sim.step(0.1 * s);
      ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
      splits += r.splits;
      ASSERT_GT(sphere->min_distance(sim.x()), 0.1) << "step " << s;
    }
    if (carrier) {
      EXPECT_EQ(splits, 0);
    }
    else EXPECT_GE(splits, 5);
    // Carried along rigidly: the cube's free vertices follow the pins.
    EXPECT_NEAR(sim.x()(Eigen::seqN(0, m.vertex_count(), 3)).mean(), 2.5, 1e-6) << (carrier ? "carried" : "held");
  }
}

TEST(ShapeColliderTerm, PinsDrivingTheSurfaceIntoAColliderStopTheRunWithOneLine) {
  // The cube's bottom face pinned and moved down 0.5 onto a plane 0.1 below it: no split can keep the
  // pinned vertices clear; the step fails with the reason, the state stays finite and separated.
  const VolumeMesh m = box_tets(2);
  SimulationSetup setup = cube_setup(m, Integrator::quasi_static);
  KinematicSet bottom = bottom_pins(m, {Translate{Vec3(0, -0.5, 0), 0.0, 1.0}});
  setup.kinematic.push_back(bottom);
  auto ground = std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), ColliderShape{Shape::plane, Vec3(0, -1.1, 0), Vec3(0, 1, 0), 0.0}, ColliderPose{}, 0.02, 1e4);
  setup.terms.push_back(ground);
  Simulation sim(std::move(setup));
  bool failed = false;
  for (int s = 1; s <= 5 && !failed; ++s) {
    const StepReport r = sim.step(0.2 * s);
    if (!r.converged) {
      failed = true;
      EXPECT_NE(r.failure.find("cannot move from t = "), std::string::npos) << r.failure;
      EXPECT_GT(r.splits, 0);
    }
    ASSERT_TRUE(sim.x().allFinite());
    ASSERT_GT(ground->min_distance(sim.x()), 0.0) << "step " << s;
  }
  EXPECT_TRUE(failed);
}

TEST(MeshColliderTerm, CollidersOutOfRangeChangeNothingBitForBit) {
  // A spinning, falling cube with a moving sphere, box and slab far away: the same states as without.
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const auto run = [&](bool colliders) {
    SimulationSetup setup = cube_setup(m, Integrator::backward_euler);
    setup.gravity = Vec3(0, -9.8, 0);
    if (colliders) {
      const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(t, 0, 0)); };
      setup.terms.push_back(std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), sphere(), [](double t) {
        return Eigen::Affine3d(Eigen::Translation3d(5, t, 0));
      }, 0.02, 1e8));
      setup.terms.push_back(std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface_of(m), "test"), ColliderShape{Shape::box, Vec3(-6, 0, 0), Vec3(1, 1, 1), 0}, pose, 0.02, 1e8));
      const Slab slab(Vec3(-2, 8, -2), Vec3(2, 9, 2));
      setup.terms.push_back(std::make_shared<MeshColliderTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, slab.V, slab.T, pose, 0.02, 1e8));
    }
    Simulation sim(std::move(setup));
    SimulationState state = sim.state();
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v) state.aux[3 * v + 2] = 0.5 * m.vertices(1, v);
    sim.restore(state);
    std::vector<Eigen::VectorXd> xs;
    for (int s = 1; s <= 5; ++s) {
      EXPECT_TRUE(sim.step(0.01 * s).converged);
      xs.push_back(sim.x());
    }
    return xs;
  };
  const auto a = run(false), b = run(true);
  for (std::size_t s = 0; s < a.size(); ++s) ASSERT_EQ(a[s], b[s]) << "step " << s;
}

TEST(ShapeColliderTerm, BadArgumentsThrow) {
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), {Shape::sphere, Vec3::Zero(), Vec3::Zero(), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), {Shape::box, Vec3::Zero(), Vec3(1, 0, 1), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), {Shape::plane, Vec3::Zero(), Vec3::Zero(), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), sphere(), {}, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({-1}, "test"), sphere(), {}, 0.1, 1.0), std::invalid_argument);
  const ColliderPose shear = [](double) {
    Eigen::Affine3d A = Eigen::Affine3d::Identity();
    A.linear()(0, 1) = 0.5;
    return A;
  };
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), sphere(), shear, 0.1, 1.0), std::invalid_argument);
  const Slab slab(Vec3(0, 0, 0), Vec3(1, 1, 1));
  Eigen::Matrix3Xi bad = slab.T;
  bad(0, 0) = 8;
  EXPECT_THROW(MeshColliderTerm(slab.T, EmbeddedPoints::every(slab.V.cols()), slab.V, slab.V, bad, {}, 0.1, 1.0), std::invalid_argument);
}

TEST(MotionTransform, MovesPointsAsTheScriptedMotionDoes) {
  Eigen::Matrix3Xd P(3, 3);
  P << 0, 1, 0.5, 0, 0, 2, 1, 0, 0.3;
  const std::vector<Motion> motions{Translate{Vec3(1, 2, 3), 0.0, 1.0}, Rotate{Vec3(0, 0, 1), 1.0, std::nullopt, 0.5, 2.0},
                                    Scale{Vec3(2, 1, 0.5), std::nullopt, 0.0, 2.0}};
  const ScriptedMotion scripted(P, motions);
  for (double t : {0.0, 0.3, 0.7, 1.5, 3.0}) {
    Eigen::Matrix3Xd Q;
    scripted.targets(t, Q);
    const Eigen::Affine3d A = motion_transform(motions, P.rowwise().mean(), t);
    EXPECT_LT(((A.linear() * P).colwise() + A.translation() - Q).norm(), 1e-12) << "t = " << t;
  }
}


// ---- embedded points (a flesh's render surface): the colliding points p = W x, derivatives through the
// weights, steps bounded on the points' motion W dx.

/// Each point of P in a cell of its own: a cube of side 0.25 (trilinear weights, 8 vertices) or a tet
/// (barycentric weights, 4 vertices) around it at random, the cells' vertices then moved at random by up to
/// `jitter` (so that x → p is not affine in a cube).
struct EmbeddedCells {
  Eigen::Matrix3Xd rest;  ///< the cells' vertices at rest
  Eigen::MatrixXi vertex;
  Eigen::MatrixXd weight;
  Eigen::VectorXd x;      ///< the cells' vertices moved
  EmbeddedCells(const Eigen::Matrix3Xd& P, bool hexes, unsigned seed, double jitter = 0.003) {
    const int k = hexes ? 8 : 4;
    const Eigen::Index n = P.cols();
    rest.resize(3, k * n);
    vertex.resize(k, n);
    weight.resize(k, n);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> inner(0.2, 0.8), unit(-1.0, 1.0);
    const double side = 0.25;
    for (Eigen::Index i = 0; i < n; ++i) {
      const Vec3 p = P.col(i);
      for (int c = 0; c < k; ++c) vertex(c, i) = static_cast<int>(k * i + c);
      if (hexes) {
        const Vec3 u(inner(rng), inner(rng), inner(rng));
        for (int c = 0; c < 8; ++c) {
          const Vec3 bit(c & 1, (c >> 1) & 1, (c >> 2) & 1);
          rest.col(k * i + c) = p + side * (bit - u);
          weight(c, i) = (bit[0] ? u[0] : 1 - u[0]) * (bit[1] ? u[1] : 1 - u[1]) * (bit[2] ? u[2] : 1 - u[2]);
        }
      } else {
        // Three vertices at random, the fourth where the barycentric weights b put p.
        Eigen::Vector4d b(inner(rng), inner(rng), inner(rng), inner(rng));
        b /= b.sum();
        Vec3 sum = Vec3::Zero();
        for (int c = 1; c < 4; ++c) {
          rest.col(k * i + c) = p + side * Vec3(unit(rng), unit(rng), unit(rng)) + side * Vec3::Unit(c - 1);
          sum += b[c] * rest.col(k * i + c);
        }
        rest.col(k * i) = (p - sum) / b[0];
        for (int c = 0; c < 4; ++c) weight(c, i) = b[c];
      }
    }
    x = flatten(rest);
    std::uniform_real_distribution<double> move(-jitter, jitter);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += move(rng);
  }
  [[nodiscard]] EmbeddedPoints points() const { return {vertex, weight, "test", rest.cols()}; }
};

/// Wᵀ g: a gradient over the points pulled back to the cells' vertices.
Eigen::VectorXd pulled_back(const EmbeddedCells& e, const Eigen::VectorXd& gp) {
  Eigen::VectorXd gx = Eigen::VectorXd::Zero(e.x.size());
  for (Eigen::Index i = 0; i < e.vertex.cols(); ++i)
    for (Eigen::Index c = 0; c < e.vertex.rows(); ++c) gx.segment<3>(3 * e.vertex(c, i)) += e.weight(c, i) * gp.segment<3>(3 * i);
  return gx;
}

TEST(ShapeColliderTerm, EmbeddedPointsMatchFiniteDifferencesThroughTheirWeights) {
  const double dhat = 0.1, d = 0.04;
  const Eigen::Affine3d pose = tilted_pose(0.7);
  const ColliderShape plane{Shape::plane, Vec3(0, 0, 0), Vec3(0, 2, 0), 0.0};
  for (const ColliderShape& shape : {sphere(), capsule(), box(), plane})
    for (const bool hexes : {true, false}) {
      SCOPED_TRACE(fmt_kind(shape) + (hexes ? " in hexes" : " in tets"));
      const std::vector<std::pair<Vec3, Vec3>> at =
          shape.kind == Shape::plane ? std::vector<std::pair<Vec3, Vec3>>{{Vec3(0.2, 0, 0.1), Vec3(0, 1, 0)}, {Vec3(-0.3, 0, 0.4), Vec3(0, 1, 0)}}
                                    : surface_probes(shape);
      const EmbeddedCells e(near(at, d, pose), hexes, 21);
      ShapeColliderTerm term(EmbeddedPoints(e.vertex, e.weight, "test", -1), shape, tilted_pose, dhat, 10.0);
      term.at_time(0.7);
      ASSERT_EQ(term.point_count(), static_cast<Eigen::Index>(at.size()));
      for (Eigen::Index i = 0; i < term.point_count(); ++i) {  // the cells' jitter moves the points a little
        EXPECT_NEAR(term.point_distance(e.x, i), 1.3 * d, 0.02) << "point " << i;
        EXPECT_LT(term.point_distance(e.x, i), dhat);
      }
      expect_fd(term, unflatten(e.x), "embedded");  // gradient, Hessian, and the projected Hessian PSD
      // The same shape against the points given as plain vertices: the same energy, and its gradient
      // pulled back by Wᵀ.
      const Eigen::Matrix3Xd P = e.points().points(e.x);
      ShapeColliderTerm direct(EmbeddedPoints::plain(iota_ids(P.cols()), "test"), shape, tilted_pose, dhat, 10.0);
      direct.at_time(0.7);
      EXPECT_NEAR(term.energy(e.x), direct.energy(flatten(P)), 1e-12 * direct.energy(flatten(P)));
      const Eigen::VectorXd gx = pulled_back(e, assembled(direct, flatten(P), PsdProjection::none).second);
      EXPECT_LE((assembled(term, e.x, PsdProjection::none).second - gx).norm(), 1e-12 * gx.norm());
    }
}

TEST(ShapeColliderTerm, IdentityWeightsGiveTheDirectTerm) {
  const Eigen::Affine3d pose = tilted_pose(0.7);
  for (const ColliderShape& shape : {sphere(), capsule(), box()}) {
    const Eigen::Matrix3Xd X = near(surface_probes(shape), 0.03, pose);
    const auto n = X.cols();
    ShapeColliderTerm direct(EmbeddedPoints::plain(iota_ids(n), "test"), shape, tilted_pose, 0.1, 10.0);
    ShapeColliderTerm embedded(identity_through_weights(n), shape, tilted_pose, 0.1, 10.0);
    direct.at_time(0.7);
    embedded.at_time(0.7);
    const Eigen::VectorXd x = flatten(X);
    EXPECT_EQ(direct.energy(x), embedded.energy(x));
    EXPECT_GT(direct.energy(x), 0.0);
    for (const PsdProjection p : {PsdProjection::none, PsdProjection::clamp}) {
      const auto [Hd, gd] = assembled(direct, x, p);
      const auto [He, ge] = assembled(embedded, x, p);
      EXPECT_EQ(gd, ge);
      EXPECT_EQ(Hd, He);
    }
    std::mt19937_64 rng(2);
    std::normal_distribution<double> g(0.0, 0.3);
    for (int trial = 0; trial < 10; ++trial) {
      Eigen::VectorXd dx(x.size());
      for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = g(rng);
      EXPECT_EQ(direct.max_step(x, dx), embedded.max_step(x, dx));
      EXPECT_EQ(direct.sweep(x, dx, 0.6, 0.8), embedded.sweep(x, dx, 0.6, 0.8));
    }
  }
}

TEST(ShapeColliderTerm, EmbeddedStepsAndSweepsKeepEveryPointOutside) {
  // Points in deformed cubes near a capsule and a box; random steps of the cells (max_step, the shape at
  // its pose) and random steps while the shape moves (sweep, a translation: exact). Along the allowed part
  // every point keeps a tenth of its distance; many steps are limited.
  int limited = 0;
  for (const ColliderShape& shape : {capsule(), box()}) {
    const Eigen::Affine3d pose = tilted_pose(0.3);
    const EmbeddedCells e(near(surface_probes(shape), 0.05, pose), true, 5, 0.01);
    ShapeColliderTerm term(EmbeddedPoints(e.vertex, e.weight, "test", -1), shape, tilted_pose, 0.1, 1.0);
    const Vec3 drift(0.2, -0.4, 0.3);
    ShapeColliderTerm moving(EmbeddedPoints(e.vertex, e.weight, "test", -1), shape, [&](double t) { return Eigen::Translation3d(t * drift) * tilted_pose(0.3); }, 0.1, 1.0);
    term.at_time(0.3);
    std::mt19937_64 rng(9);
    std::normal_distribution<double> g(0.0, 0.2);
    for (int trial = 0; trial < 40; ++trial) {
      Eigen::VectorXd dx(e.x.size());
      for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = g(rng);
      const double alpha = term.max_step(e.x, dx);
      moving.at_time(0.0);
      const double beta = moving.sweep(e.x, dx, 0.0, 1.0);
      ASSERT_GT(alpha, 0.0);
      ASSERT_GT(beta, 0.0);
      limited += (alpha < 1.0) + (beta < 1.0);
      for (Eigen::Index i = 0; i < term.point_count(); ++i) {
        const double d0 = term.point_distance(e.x, i);
        ASSERT_GT(d0, 0.0);
        for (int s = 0; s <= 100; ++s) {
          ASSERT_GE(term.point_distance(e.x + (alpha * s / 100.0) * dx, i), 0.1 * d0 * (1 - 1e-9)) << "trial " << trial;
          moving.at_time(beta * s / 100.0);
          ASSERT_GE(moving.point_distance(e.x + (beta * s / 100.0) * dx, i), 0.1 * d0 * (1 - 1e-9)) << "trial " << trial;
        }
      }
    }
  }
  EXPECT_GT(limited, 30);
}

TEST(MeshColliderTerm, AnEmbeddedSurfaceMatchesFiniteDifferencesAndItsStepsOnThePoints) {
  // MatchesFiniteDifferencesWithEachPairKind's tet and triangle pair, the tet's vertices now points embedded
  // in cubes or tets: derivatives by finite differences, the projected Hessian PSD; against the same
  // surface given directly at the points: the same energy, the gradient pulled back by Wᵀ, and max_step and
  // sweep equal to the direct term's on the points' motion W dx.
  const TetUnderTriangles fixture;
  const Eigen::Matrix3Xd& X = fixture.X;
  const Eigen::Matrix3Xi& F = fixture.F;
  const Eigen::Matrix3Xd& W = fixture.W;
  const Eigen::Matrix3Xi& T = fixture.T;
  const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.01 * t)); };
  for (const bool hexes : {true, false})
    for (const unsigned seed : {1u, 2u}) {
      SCOPED_TRACE(hexes ? "hexes" : "tets");
      const EmbeddedCells e(X, hexes, seed, 0.005);
      MeshColliderTerm term(F, EmbeddedPoints(e.vertex, e.weight, "test", e.rest.cols()), e.rest, W, T, pose, 0.3, 5.0);
      term.at_time(1.0);
      const Eigen::VectorXd x = e.x;
      Problem problem(DofMap(std::vector<std::uint8_t>(static_cast<std::size_t>(x.size()), 0)));
      problem.add(term);
      ASSERT_GT(term.energy(x), 0.0);
      ASSERT_TRUE(std::isfinite(term.energy(x)));
      const FdErrors fd = problem_fd_errors(problem, x);
      EXPECT_LE(fd.gradient, 1e-6);
      EXPECT_LE(fd.hessian, 1e-6);
      const Eigen::MatrixXd Hp = assembled(term, x, PsdProjection::clamp).first;
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hp).eigenvalues().minCoeff(), -1e-9 * Hp.norm());

      const EmbeddedPoints points = e.points();
      const Eigen::Matrix3Xd P = points.points(x);
      MeshColliderTerm direct(F, EmbeddedPoints::every(points.points(flatten(e.rest)).cols()), points.points(flatten(e.rest)), W, T, pose, 0.3, 5.0);
      direct.at_time(1.0);
      EXPECT_NEAR(term.energy(x), direct.energy(flatten(P)), 1e-12 * direct.energy(flatten(P)));
      EXPECT_NEAR(term.min_distance(x), direct.min_distance(flatten(P)), 1e-15);
      const Eigen::VectorXd gx = pulled_back(e, assembled(direct, flatten(P), PsdProjection::none).second);
      EXPECT_LE((assembled(term, x, PsdProjection::none).second - gx).norm(), 1e-12 * gx.norm());

      // Steps: a cube's surface embedded likewise under a slab (MaxStepAndSweepNeverCrossOnRandomSteps),
      // random steps of the cells towards it and random jumps of the slab.
      const VolumeMesh m = box_tets(2);
      const Eigen::Matrix3Xi G = boundary_triangles(m);
      const Slab slab(Vec3(-2, 1.05, -2), Vec3(2, 1.25, 2));
      const EmbeddedCells c(m.vertices, hexes, seed, 0.005);
      const EmbeddedPoints cube = c.points();
      const Eigen::VectorXd y = c.x, q = flatten(cube.points(y));
      std::mt19937_64 rng(seed);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      int crossing = 0;
      for (int k = 0; k < 20; ++k) {
        const Vec3 jump(0.3 * u(rng), -0.6 - 0.8 * std::abs(u(rng)), 0.3 * u(rng));
        const ColliderPose jumping = [jump](double t) { return Eigen::Affine3d(Eigen::Translation3d(t * jump)); };
        MeshColliderTerm embedded(G, EmbeddedPoints(c.vertex, c.weight, "test", c.rest.cols()), c.rest, slab.V, slab.T, jumping, 0.02, 1.0);
        MeshColliderTerm plain(G, EmbeddedPoints::every(cube.points(flatten(c.rest)).cols()), cube.points(flatten(c.rest)), slab.V, slab.T, jumping, 0.02, 1.0);
        Eigen::VectorXd dx(y.size());
        for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = 0.05 * u(rng) + (i % 3 == 1 ? 1.0 + 0.5 * std::abs(u(rng)) : 0.0);
        const Eigen::VectorXd dq = flatten(cube.points(dx));
        const double a = embedded.max_step(y, dx);
        EXPECT_EQ(a, plain.max_step(q, dq));
        ASSERT_GT(a, 0.0);
        crossing += surfaces_cross(G, cube.points(Eigen::VectorXd(y + dx)), slab.T, slab.V);
        ASSERT_FALSE(surfaces_cross(G, cube.points(Eigen::VectorXd(y + a * dx)), slab.T, slab.V)) << "step " << k;
        ASSERT_GT(embedded.min_distance(y + a * dx), 0.0);
        const Eigen::VectorXd still = Eigen::VectorXd::Zero(y.size());
        const double b = embedded.sweep(y, still, 0.0, 1.0);
        EXPECT_EQ(b, plain.sweep(q, Eigen::VectorXd::Zero(q.size()), 0.0, 1.0));
        const Eigen::VectorXd small = 0.1 * dx;
        EXPECT_EQ(embedded.sweep(y, small, 0.0, 1.0), plain.sweep(q, flatten(cube.points(small)), 0.0, 1.0));
        ASSERT_GT(b, 0.0);
        crossing += surfaces_cross(G, cube.points(y), slab.T, slab.V.colwise() + jump);
        embedded.at_time(b);
        ASSERT_FALSE(surfaces_cross(G, cube.points(y), slab.T, embedded.collider_vertices())) << "jump " << k;
      }
      EXPECT_GT(crossing, 20);  // most full steps and jumps do cross
    }
}

TEST(MeshColliderTerm, IdentityWeightsGiveTheDirectTerm) {
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const Slab slab(Vec3(-2, 1.05, -2), Vec3(2, 1.25, 2));
  const auto n = m.vertex_count();
  MeshColliderTerm direct(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, slab.V, slab.T, ColliderPose{}, 0.1, 3.0);
  MeshColliderTerm embedded(F, identity_through_weights(n), m.vertices, slab.V, slab.T, ColliderPose{}, 0.1, 3.0);
  const Eigen::VectorXd x = flatten(m.vertices);
  EXPECT_EQ(direct.energy(x), embedded.energy(x));
  EXPECT_GT(direct.energy(x), 0.0);
  for (const PsdProjection p : {PsdProjection::none, PsdProjection::clamp}) {
    const auto [Hd, gd] = assembled(direct, x, p);
    const auto [He, ge] = assembled(embedded, x, p);
    EXPECT_EQ(gd, ge);
    EXPECT_LE((Hd - He).norm(), 1e-14 * Hd.norm());  // blocks added in the other orientation: symmetric to rounding
    EXPECT_GT(Hd.norm(), 0.0);
  }
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index v = 0; v < n; ++v) dx[3 * v + 1] = 0.5;
  EXPECT_EQ(direct.max_step(x, dx), embedded.max_step(x, dx));
  EXPECT_LT(direct.max_step(x, dx), 1.0);
}

TEST(ShapeColliderTerm, BadEmbeddingsThrow) {
  const Eigen::MatrixXi ids = Eigen::RowVectorXi::LinSpaced(4, 0, 3);
  const Eigen::MatrixXd ones = Eigen::RowVectorXd::Ones(4);
  EXPECT_NO_THROW(ShapeColliderTerm(EmbeddedPoints(ids, ones, "test", -1), sphere(), ColliderPose{}, 0.1, 1.0));
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(ids, Eigen::MatrixXd::Ones(2, 4), "test", -1), sphere(), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  Eigen::MatrixXd nan = ones;
  nan(0, 2) = NAN;
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(ids, nan, "test", -1), sphere(), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  Eigen::MatrixXi negative = ids;
  negative(0, 1) = -1;
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(negative, ones, "test", -1), sphere(), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  const Slab slab(Vec3(-2, 1.05, -2), Vec3(2, 1.25, 2));
  Eigen::Matrix3Xi F(3, 1);
  F << 0, 1, 2;
  Eigen::MatrixXi far = ids;
  far(0, 3) = 4;  // beyond the volume's 4 vertices
  const Eigen::Matrix3Xd rest = Eigen::Matrix3Xd::Random(3, 4);
  EXPECT_NO_THROW(MeshColliderTerm(F, EmbeddedPoints(ids, ones, "test", rest.cols()), rest, slab.V, slab.T, ColliderPose{}, 0.1, 1.0));
  EXPECT_THROW(MeshColliderTerm(F, EmbeddedPoints(far, ones, "test", rest.cols()), rest, slab.V, slab.T, ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(MeshColliderTerm(F, EmbeddedPoints(ids, nan, "test", rest.cols()), rest, slab.V, slab.T, ColliderPose{}, 0.1, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace snh
