// Contact in whole simulations the issue names (issue 16): a bar bent onto itself (both ends clamped and
// brought together until the buckled bar folds into a loop whose strands meet), and a ball pressed by a
// moving mesh collider. Each runs with and without contact and checks every step with the brute-force
// surface tests of tests/contact/surface_checks.hpp: with contact nothing intersects and every distance
// stays positive; without it the same motion does intersect (so the check can fail).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>
#include <vector>

#include "contact/surface_checks.hpp"
#include "sim/face_pins.hpp"
#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/sim/simulation.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::unflatten;

/// The tets of box_tets(res) whose centroids lie in [lo, hi], with only the vertices they use (renumbered
/// in the box's order).
VolumeMesh cut_box(int res, const Vec3& lo, const Vec3& hi) {
  const VolumeMesh box = box_tets(res);
  std::vector<int> kept, id(static_cast<std::size_t>(box.vertex_count()), -1);
  for (Eigen::Index c = 0; c < box.cells.cols(); ++c) {
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centroid += box.vertices.col(box.cells(k, c)) / 4.0;
    if ((centroid.array() >= lo.array()).all() && (centroid.array() <= hi.array()).all()) {
      kept.push_back(static_cast<int>(c));
      for (int k = 0; k < 4; ++k) id[static_cast<std::size_t>(box.cells(k, c))] = 0;
    }
  }
  VolumeMesh m;
  m.type = CellType::tet4;
  int n = 0;
  for (int& i : id)
    if (i == 0) i = n++;
  m.vertices.resize(3, n);
  for (std::size_t v = 0; v < id.size(); ++v)
    if (id[v] >= 0) m.vertices.col(id[v]) = box.vertices.col(static_cast<Eigen::Index>(v));
  m.cells.resize(4, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t c = 0; c < kept.size(); ++c)
    for (int k = 0; k < 4; ++k) m.cells(k, static_cast<Eigen::Index>(c)) = id[static_cast<std::size_t>(box.cells(k, kept[c]))];
  return m;
}

struct BarRun {
  int steps_intersecting = 0, first_intersecting = -1, newton = 0;
  double closest = INFINITY;          ///< the term's smallest pair distance over the steps (d̂ with none in range)
  double closest_checked = INFINITY;  ///< surface_min_distance over the steps (contact runs)
  bool converged = true;
};

/// A bar of 16 × 1 × 2 cells (2 long, 0.125 thick, 0.25 wide; 192 tets), its left end clamped and its
/// right end pushed towards it by `shortening` over `steps` quasi-static steps,, started bowed across its thin side (so
/// that it buckles that way).
BarRun bend_bar(bool contact, double shortening, int steps, double bow) {
  const VolumeMesh m = cut_box(16, Vec3(-1, -1, -1), Vec3(1, -0.875, -0.75));
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  SimulationSetup setup;
  setup.mesh = m;
  setup.materials = {make_material("stable_neo_hookean", {1e4, 1e5})};
  setup.density = 1.0;
  setup.integrator = Integrator::quasi_static;
  setup.newton.tolerance = 1e-6 * 2.9e4 * 0.125 * 0.125;  // the scenes' rule: 1e-6 E ℓ²
  setup.newton.relative_step_tolerance = 1e-8;
  setup.newton.max_iterations = 400;
  setup.linear.name = "ldlt";
  setup.kinematic.push_back(face_pins(m, 0, -1.0, {}, "left"));
  setup.kinematic.push_back(face_pins(m, 0, 1.0, {Translate{Vec3(-shortening, 0, 0), 0.0, 1.0}}, "right"));
  // Started bowed upwards in its first clamped mode, (1 − cos 2πs)/2 along it, so that it buckles that way.
  Eigen::Matrix3Xd start = m.vertices;
  for (Eigen::Index v = 0; v < start.cols(); ++v) start(1, v) += 0.5 * bow * (1.0 - std::cos(std::numbers::pi * (start(0, v) + 1.0)));
  setup.initial = Eigen::Map<const Eigen::VectorXd>(start.data(), start.size());
  std::shared_ptr<ContactTerm> term;
  if (contact) {
    term = std::make_shared<ContactTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, 0.01, 3.6e7);
    setup.terms.push_back(term);
  }
  Simulation sim(std::move(setup));
  BarRun run;
  for (int s = 1; s <= steps; ++s) {
    const StepReport r = sim.step(static_cast<double>(s) / steps);
    run.newton += r.newton.iterations;
    if (!r.converged) {
      run.converged = false;
      std::cout << "step " << s << ": " << r.failure << "\n";
      break;
    }
    const Eigen::Matrix3Xd V = unflatten(sim.x());
    if (surface_intersects(F, V)) {
      ++run.steps_intersecting;
      if (run.first_intersecting < 0) run.first_intersecting = s;
    }
    if (term) {
      run.closest = std::min(run.closest, term->min_distance(sim.x()));
      run.closest_checked = std::min(run.closest_checked, surface_min_distance(F, V));
    }
  }
  return run;
}

TEST(ContactScenes, ABarBentOntoItselfNeverPassesThroughItself) {
  // Shortened by 1.76 of its 2 in 44 steps the clamped bar buckles into a loop whose strands meet near the
  // middle; without contact they pass through each other in the last steps.
  const BarRun without = bend_bar(false, 1.76, 44, 0.05);
  const BarRun with = bend_bar(true, 1.76, 44, 0.05);
  for (const BarRun* r : {&without, &with})
    std::cout << (r == &with ? "with" : "without") << " contact: " << r->newton << " Newton iterations, " << r->steps_intersecting
              << " steps intersecting (first " << r->first_intersecting << "), smallest distance " << r->closest_checked
              << " (the term's " << r->closest << ")\n";
  ASSERT_TRUE(without.converged);
  EXPECT_GT(without.steps_intersecting, 0);
  ASSERT_TRUE(with.converged);
  EXPECT_EQ(with.steps_intersecting, 0);
  EXPECT_GT(with.closest_checked, 0.0);  // the brute-force distance over the whole surface, every step
  EXPECT_LT(with.closest, 0.01);         // the strands did come within d̂: the barrier held them
}

/// The ball of radius 1: box_tets(res) with every vertex p moved to p |p|∞ / |p| (the cube's shells of
/// constant |p|∞ onto spheres).
VolumeMesh ball_tets(int res) {
  VolumeMesh m = box_tets(res);
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) {
    const Vec3 p = m.vertices.col(v);
    if (p.norm() > 0.0) m.vertices.col(v) = p * p.cwiseAbs().maxCoeff() / p.norm();
  }
  return m;
}

struct BallRun {
  int steps_intersecting = 0, first_intersecting = -1, newton = 0, splits = 0;
  double closest = INFINITY, top = 0.0;  ///< the term's smallest distance; the ball's highest point at the end
  double closest_checked = INFINITY;     ///< surface_min_distance over both surfaces, every step (contact runs)
  bool converged = true;
};

/// The ball (6 × 6 × 6 cells cut to tets and rounded, 1 296 tets), its bottom cap held, pressed quasi-
/// statically by a bar (a box 0.4 × 0.4 × 2.4 along z) turned 45° about z, its lowest edge first, coming
/// down by `travel` over `steps` steps from 0.05 above the ball. Checked at every step over both surfaces together: no two
/// triangles (of the ball, of the box, or one of each) intersect.
BallRun press_ball(bool contact, double travel, int steps, Integrator integrator = Integrator::quasi_static) {
  const VolumeMesh m = ball_tets(6);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  for (Eigen::Index c = 0; c < m.cells.cols(); ++c) {  // the rounding keeps every tet positive
    const Vec3 a = m.vertices.col(m.cells(0, c));
    EXPECT_GT((m.vertices.col(m.cells(1, c)) - a).dot((m.vertices.col(m.cells(2, c)) - a).cross(m.vertices.col(m.cells(3, c)) - a)), 0.0);
  }
  SimulationSetup setup;
  setup.mesh = m;
  setup.materials = {make_material("stable_neo_hookean", {1e4, 1e5})};
  setup.integrator = integrator;
  setup.dt = 1.0 / steps;
  setup.density = 1e3;
  const double cell = 1.0 / 3.0;
  setup.newton.tolerance = 1e-6 * 2.9e4 * cell * cell;
  setup.newton.relative_step_tolerance = 1e-8;
  setup.linear.name = "ldlt";
  KinematicSet cap;
  cap.name = "cap";
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    if (m.vertices(1, v) < -0.85) cap.vertices.push_back(static_cast<int>(v));
  cap.provider = std::make_shared<ScriptedMotion>(m.vertices(Eigen::all, cap.vertices), std::vector<Motion>{});
  setup.kinematic.push_back(cap);
  // The bar, turned 45° about z: its lowest edge along z over the ball's top, 0.05 above it.
  const Slab box(Vec3(-0.2, -0.2, -1.2), Vec3(0.2, 0.2, 1.2));
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(45.0 * std::numbers::pi / 180.0, Vec3::UnitZ()).toRotationMatrix();
  Eigen::Matrix3Xd B = turn * box.V;
  B.row(1).array() += 1.05 - B.row(1).minCoeff();
  const ColliderPose pose = [travel](double t) { return Eigen::Affine3d(Eigen::Translation3d(0, -travel * t, 0)); };
  std::shared_ptr<MeshColliderTerm> term;
  if (contact) {
    term = std::make_shared<MeshColliderTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, B, box.T, pose, 0.02, 2.9e4 * cell / (0.02 * 0.02));
    setup.terms.push_back(term);
  }
  Simulation sim(std::move(setup));
  // Both surfaces as one: the box's vertices after the ball's.
  const Eigen::Index n = m.vertex_count();
  Eigen::Matrix3Xi both(3, F.cols() + box.T.cols());
  both << F, box.T.array() + static_cast<int>(n);
  Eigen::Matrix3Xd V(3, n + B.cols());
  BallRun run;
  for (int s = 1; s <= steps; ++s) {
    const double t = static_cast<double>(s) / steps;
    const StepReport r = sim.step(t);
    run.newton += r.newton.iterations;
    run.splits += r.splits;
    if (!r.converged) {
      run.converged = false;
      std::cout << "step " << s << ": " << r.failure << "\n";
      break;
    }
    V << unflatten(sim.x()), pose(t) * B;
    if (surface_intersects(both, V)) {
      ++run.steps_intersecting;
      if (run.first_intersecting < 0) run.first_intersecting = s;
    }
    if (term) run.closest = std::min(run.closest, term->min_distance(sim.x()));
    if (term) run.closest_checked = std::min(run.closest_checked, surface_min_distance(both, V));
  }
  run.top = sim.x()(Eigen::seqN(1, n, 3)).maxCoeff();
  return run;
}

TEST(ContactScenes, ABallPressedByAMovingMeshColliderNeverPassesIntoIt) {
  // The bar comes down 0.4 in 8 steps, 0.05 a step (more than d̂ = 0.02: steps are split where its sweep
  // is not clear); the ball's top starts at 1.
  const BallRun without = press_ball(false, 0.4, 8);
  const BallRun with = press_ball(true, 0.4, 8);
  for (const BallRun* r : {&without, &with})
    std::cout << (r == &with ? "with" : "without") << " contact: " << r->newton << " Newton iterations, " << r->splits
              << " splits, " << r->steps_intersecting << " steps intersecting (first " << r->first_intersecting
              << "), smallest distance " << r->closest << ", top at " << r->top << "\n";
  ASSERT_TRUE(without.converged);
  EXPECT_GT(without.steps_intersecting, 0);
  ASSERT_TRUE(with.converged);
  EXPECT_EQ(with.steps_intersecting, 0);
  EXPECT_GT(with.closest_checked, 0.0);
  EXPECT_LT(with.closest, 0.02);  // in range of the barrier: it held the bar off
  EXPECT_GT(with.splits, 0);      // the bar's sweeps were not clear: the steps were cut
  EXPECT_LT(with.top, 1.0 - 0.25);  // pressed down, not passed through
}

TEST(ContactScenes, ABallPressedByAMovingMeshColliderHoldsByEveryDynamicIntegrator) {
  // The same press made dynamically (steps of 1/8 s, density 1000): a step whose collider sweep is not clear is
  // split, and each part is a whole step of the integrator (TR-BDF2: both of its stages).
  for (const Integrator integrator : {Integrator::backward_euler, Integrator::bdf2, Integrator::tr_bdf2}) {
    SCOPED_TRACE(integrator_name(integrator));
    const BallRun with = press_ball(true, 0.4, 8, integrator);
    std::cout << integrator_name(integrator) << ": " << with.newton << " Newton iterations, " << with.splits
              << " splits, smallest distance " << with.closest << ", top at " << with.top << "\n";
    ASSERT_TRUE(with.converged);
    EXPECT_EQ(with.steps_intersecting, 0);
    EXPECT_GT(with.closest_checked, 0.0);
    EXPECT_GT(with.splits, 0);
    EXPECT_LT(with.top, 1.0 - 0.25);
  }
}

}  // namespace
}  // namespace snh
