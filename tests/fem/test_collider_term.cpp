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
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/sim/simulation.hpp"
#include "contact/surface_checks.hpp"
#include "fem/problem_fd.hpp"

namespace snh {
namespace {

using Kind = ColliderShape::Kind;

Eigen::VectorXd flatten(const Eigen::Matrix3Xd& X) { return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size()); }
Eigen::Matrix3Xd unflatten(const Eigen::VectorXd& x) { return Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3); }

/// A similarity: rotation about a tilted axis, uniform scale 1.3, translation.
Eigen::Affine3d tilted_pose(double t) {
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  A.linear() = 1.3 * Eigen::AngleAxisd(0.4 + t, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  A.translation() = Vec3(0.3, -0.2, 0.5) + t * Vec3(0.1, 0.0, 0.0);
  return A;
}

ColliderShape sphere() { return {Kind::sphere, Vec3(0.1, 0.2, -0.1), Vec3::Zero(), 0.7}; }
ColliderShape capsule() { return {Kind::capsule, Vec3(-0.5, 0, 0), Vec3(0.5, 0.2, 0), 0.3}; }
ColliderShape box() { return {Kind::box, Vec3(0, 0.1, 0), Vec3(0.4, 0.3, 0.6), 0.0}; }

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

TEST(ShapeColliderTerm, MatchesFiniteDifferencesNearCapsEdgesAndCorners) {
  const double dhat = 0.1, d = 0.04;
  const Eigen::Affine3d pose = tilted_pose(0.7);
  for (const ColliderShape& shape : {sphere(), capsule(), box()}) {
    ShapeColliderTerm term({0, 1, 2, 3, 4, 5}, shape, tilted_pose, dhat, 10.0);
    term.at_time(0.7);
    std::vector<std::pair<Vec3, Vec3>> at;
    if (shape.kind == Kind::sphere) {
      for (const Vec3& n : {Vec3(1, 0, 0), Vec3(0.3, -1, 0.2), Vec3(-1, 1, 1), Vec3(0, 0, -1), Vec3(2, 1, -1), Vec3(-1, -1, 0.5)})
        at.push_back({shape.a + shape.radius * n.normalized(), n});
    } else if (shape.kind == Kind::capsule) {  // the side, both caps (on and off the axis), near where they meet
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
    // The capsule's caps and the box's edges and corners: the directions above point outward there.
    const Eigen::Matrix3Xd X = near(at, d, pose);
    for (Eigen::Index i = 0; i < X.cols(); ++i)
      EXPECT_NEAR(term.distance(flatten(X), static_cast<int>(i)), 1.3 * d, 1e-12) << "vertex " << i;
    expect_fd(term, X, shape.kind == Kind::sphere ? "sphere" : shape.kind == Kind::capsule ? "capsule" : "box");
  }
  // A moving plane: the signed distance, its derivatives, and +∞ behind it.
  ShapeColliderTerm plane({0, 1}, {Kind::plane, Vec3(0, 0, 0), Vec3(0, 2, 0), 0.0}, tilted_pose, dhat, 10.0);
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
    ShapeColliderTerm term({0}, shape, tilted_pose, 0.1, 1.0);
    term.at_time(0.3);
    for (int k = 0; k < 300; ++k) {
      Eigen::VectorXd x(3), dx(3);
      do {
        for (int i = 0; i < 3; ++i) x[i] = 2.0 * u(rng);
      } while (!(term.distance(x, 0) > 1e-3));
      for (int i = 0; i < 3; ++i) dx[i] = 3.0 * u(rng);
      const double d0 = term.distance(x, 0), alpha = term.max_step(x, dx);
      ASSERT_GT(alpha, 0.0);
      if (alpha < 1.0) ++limited;
      // Densely along the allowed part: never below a tenth of the start (up to rounding).
      for (int s = 0; s <= 400; ++s) {
        const Eigen::VectorXd y = x + (alpha * s / 400.0) * dx;
        ASSERT_GE(term.distance(y, 0), 0.1 * d0 * (1 - 1e-9)) << "step " << k << " at " << s;
      }
      // And not needlessly short: the path's first point below a tenth is close after alpha.
      if (alpha < 1.0) {
        double first = 1.0;
        for (int s = 0; s <= 2000; ++s)
          if (term.distance(x + (s / 2000.0) * dx, 0) < 0.1 * d0) {
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

TEST(MeshColliderTerm, MatchesFiniteDifferencesWithEachPairKind) {
  // One tet (simulated) under a small tilted triangle pair (the collider): a tet vertex under a collider
  // triangle, a collider vertex over a tet face, and crossing edges, all within d̂.
  Eigen::Matrix3Xd X(3, 4);
  X << 0, 1, 0, 0.3,  //
      0, 0, 1, 0.3,    //
      0, 0, 0, 0.95;
  const Eigen::Matrix3Xi F = [] {
    Eigen::Matrix3Xi f(3, 4);
    f << 0, 0, 1, 0, 2, 1, 2, 3, 1, 3, 3, 2;
    return f;
  }();
  Eigen::Matrix3Xd W(3, 4);
  W << -0.2, 0.9, 0.1, 0.6,  //
      0.25, 0.2, 0.9, 0.7,    //
      1.0, 1.02, 0.99, 0.4;
  Eigen::Matrix3Xi T(3, 2);
  T << 0, 0, 1, 2, 2, 3;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::Matrix3Xd Y = X;
    for (Eigen::Index i = 0; i < Y.size(); ++i) Y.data()[i] += u(rng);
    const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(0, 0, 0.01 * t)); };
    MeshColliderTerm term(F, X, W, T, pose, 0.3, 5.0);
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
    MeshColliderTerm term(F, m.vertices, slab.V, slab.T, pose, 0.02, 1.0);
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
KinematicSet bottom_pins(const VolumeMesh& m, std::vector<Motion> motions) {
  KinematicSet bottom;
  bottom.name = "bottom";
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    if (m.vertices(1, v) == -1.0) bottom.vertices.push_back(static_cast<int>(v));
  bottom.provider = std::make_shared<ScriptedMotion>(m.vertices(Eigen::all, bottom.vertices), std::move(motions));
  return bottom;
}

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
  auto term = std::make_shared<ShapeColliderTerm>(surface_of(m), shape, ColliderPose{}, dhat, 1e8);
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
  drop_onto({Kind::sphere, Vec3(0, -5.2, 0), Vec3::Zero(), 4.0}, "sphere");
  drop_onto({Kind::box, Vec3(0.3, -1.7, -0.2), Vec3(1.5, 0.5, 1.5), 0.0}, "box");
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
  auto term = std::make_shared<MeshColliderTerm>(F, m.vertices, slab.V, slab.T, pose, dhat, 1e9);
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
  // millionth of h and the step fails with its one line: README, "Moving colliders within a run".)
  const VolumeMesh m = box_tets(3);
  SimulationSetup setup = cube_setup(m, Integrator::backward_euler);
  const ColliderPose pose = [](double t) { return Eigen::Affine3d(Eigen::Translation3d(-10.0 * t, 0, 0)); };
  auto wall = std::make_shared<ShapeColliderTerm>(surface_of(m), ColliderShape{Kind::box, Vec3(1.6, 0, 0), Vec3(0.5, 3, 3), 0.0}, pose,
                                                  0.02, 1e8);
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

TEST(ShapeColliderTerm, PinsDrivingTheSurfaceIntoAColliderStopTheRunWithOneLine) {
  // The cube's bottom face pinned and moved down 0.5 onto a plane 0.1 below it: no split can keep the
  // pinned vertices clear; the step fails with the reason, the state stays finite and separated.
  const VolumeMesh m = box_tets(2);
  SimulationSetup setup = cube_setup(m, Integrator::quasi_static);
  KinematicSet bottom = bottom_pins(m, {Translate{Vec3(0, -0.5, 0), 0.0, 1.0}});
  setup.kinematic.push_back(bottom);
  auto ground = std::make_shared<ShapeColliderTerm>(surface_of(m), ColliderShape{Kind::plane, Vec3(0, -1.1, 0), Vec3(0, 1, 0), 0.0},
                                                    ColliderPose{}, 0.02, 1e4);
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
      setup.terms.push_back(std::make_shared<ShapeColliderTerm>(surface_of(m), sphere(), [](double t) {
        return Eigen::Affine3d(Eigen::Translation3d(5, t, 0));
      }, 0.02, 1e8));
      setup.terms.push_back(std::make_shared<ShapeColliderTerm>(surface_of(m), ColliderShape{Kind::box, Vec3(-6, 0, 0), Vec3(1, 1, 1), 0},
                                                                pose, 0.02, 1e8));
      const Slab slab(Vec3(-2, 8, -2), Vec3(2, 9, 2));
      setup.terms.push_back(std::make_shared<MeshColliderTerm>(F, m.vertices, slab.V, slab.T, pose, 0.02, 1e8));
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
  EXPECT_THROW(ShapeColliderTerm({0}, {Kind::sphere, Vec3::Zero(), Vec3::Zero(), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm({0}, {Kind::box, Vec3::Zero(), Vec3(1, 0, 1), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm({0}, {Kind::plane, Vec3::Zero(), Vec3::Zero(), 0.0}, {}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm({0}, sphere(), {}, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm({-1}, sphere(), {}, 0.1, 1.0), std::invalid_argument);
  const ColliderPose shear = [](double) {
    Eigen::Affine3d A = Eigen::Affine3d::Identity();
    A.linear()(0, 1) = 0.5;
    return A;
  };
  EXPECT_THROW(ShapeColliderTerm({0}, sphere(), shear, 0.1, 1.0), std::invalid_argument);
  const Slab slab(Vec3(0, 0, 0), Vec3(1, 1, 1));
  Eigen::Matrix3Xi bad = slab.T;
  bad(0, 0) = 8;
  EXPECT_THROW(MeshColliderTerm(slab.T, slab.V, slab.V, bad, {}, 0.1, 1.0), std::invalid_argument);
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

}  // namespace
}  // namespace snh
