// Lagged Coulomb friction against a collider (fem/friction_term.hpp): the dissipative potential's gradient
// and Hessian against finite differences (plain and embedded points, sticking and sliding slips, a moving
// and turning collider), its Hessian PSD, the force bounded by μλ and at the carried anchor zero; and
// physics: a cube on a plane under gravity tilted by θ (tan θ = 1/2, backward Euler) slides with the
// acceleration g (sin θ − μ cos θ) for μ = 0.2, stays put for μ = 0.8, and μ = 0 changes nothing bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <random>

#include "snh/fem/contact_term.hpp"
#include "snh/fem/friction_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/sim/simulation.hpp"
#include "fem/problem_fd.hpp"
#include "sim/face_pins.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using Shape = ColliderShape::Kind;

using test::flatten;

/// A similarity moving in time: turning about a tilted axis, scaled 1.3, translating.
Eigen::Affine3d turning_pose(double t) {
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  A.linear() = 1.3 * Eigen::AngleAxisd(0.4 + t, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  A.translation() = Vec3(0.3, -0.2, 0.5) + t * Vec3(0.4, 0.1, 0.0);
  return A;
}

const ColliderShape kSphere{Shape::sphere, Vec3(0.1, 0.2, -0.1), Vec3::Zero(), 0.7};

/// Points (world) at distances 0.01 … 0.06 outside the sphere at its pose at t0 = 0.2.
Eigen::Matrix3Xd near_sphere(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Affine3d A = turning_pose(0.2);
  Eigen::Matrix3Xd P(3, n);
  for (int i = 0; i < n; ++i) {
    const Vec3 dir = Vec3(g(rng), g(rng), g(rng)).normalized();
    P.col(i) = A * (kSphere.a + (kSphere.radius + (0.01 + 0.05 * i / n) / 1.3) * dir);
  }
  return P;
}

void expect_fd_and_psd(LaggedFrictionTerm& term, const Eigen::VectorXd& x, const char* what) {
  Problem problem(DofMap(std::vector<std::uint8_t>(static_cast<std::size_t>(x.size()), 0)));
  problem.add(term);
  const FdErrors e = problem_fd_errors(problem, x);
  EXPECT_LE(e.gradient, 1e-6) << what;
  EXPECT_LE(e.hessian, 1e-6) << what;
  EXPECT_GE(hessian_min_eigenvalue_ratio(problem, x, PsdProjection::none), -1e-9) << what;  // PSD unprojected
}

TEST(FrictionTerm, MatchesFiniteDifferencesWhileStickingAndSliding) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  const int n = 8;
  const Eigen::Matrix3Xd P = near_sphere(n, rng);
  const double dhat = 0.1, velocity = 1.0, t0 = 0.2, t1 = 0.3;  // ε = 0.1
  // Plain vertices.
  FrictionTerm term(EmbeddedPoints::plain({0, 1, 2, 3, 4, 5, 6, 7}, "test"), kSphere, turning_pose, dhat, 1e3, 0.6, velocity);
  term.begin_step(flatten(P), t0, t1);
  ASSERT_EQ(term.lagged_points(), n);
  ASSERT_GT(term.normal_force(), 0.0);
  EXPECT_DOUBLE_EQ(term.epsilon(), 0.1);
  // Each point where the collider carries it, then slipped by 0.02 (sticking) or 0.3 (sliding).
  const Eigen::Affine3d carry = turning_pose(t1) * turning_pose(t0).inverse();
  Eigen::Matrix3Xd X(3, n);
  for (int i = 0; i < n; ++i) X.col(i) = carry * P.col(i) + (i % 2 ? 0.3 : 0.02) * Vec3(g(rng), g(rng), g(rng)).normalized();
  expect_fd_and_psd(term, flatten(X), "plain");
  // At the anchors: no force, the energy μλ ε/3 per point.
  Eigen::Matrix3Xd anchors(3, n);
  for (int i = 0; i < n; ++i) anchors.col(i) = carry * P.col(i);
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(3 * n);
  const double e0 = term.evaluate(flatten(anchors), &grad, nullptr, PsdProjection::none);
  EXPECT_NEAR(e0, 0.6 * term.normal_force() * 0.1 / 3.0, 1e-12 * e0);
  EXPECT_LE(grad.norm(), 1e-12);
  // Coulomb: the force on a point is at most μλ, and μλ when sliding (past ε), along −u.
  grad.setZero();
  term.evaluate(flatten(X), &grad, nullptr, PsdProjection::none);
  double bound = 0.0;
  for (int i = 1; i < n; i += 2) bound += grad.segment<3>(3 * i).norm();
  double sliding_force = 0.0;  // the sliding points' μλ, from a term of them alone
  FrictionTerm sliding(EmbeddedPoints::plain({1, 3, 5, 7}, "test"), kSphere, turning_pose, dhat, 1e3, 0.6, velocity);
  sliding.begin_step(flatten(P), t0, t1);
  sliding_force = 0.6 * sliding.normal_force();
  EXPECT_NEAR(bound, sliding_force, 1e-9 * sliding_force);
  for (int i = 0; i < n; i += 2) EXPECT_LT(grad.segment<3>(3 * i).norm(), 0.6 * term.normal_force());

  // Embedded points: each the weighted sum of 8 vertices scattered about it (weights summing to 1, two
  // weights of one point on one vertex).
  const int k = 8;
  Eigen::Matrix3Xd V(3, k * n);
  Eigen::MatrixXi vertex(k, n);
  Eigen::MatrixXd weight(k, n);
  std::uniform_real_distribution<double> u(0.1, 1.0);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j) {
      vertex(j, i) = k * i + j;
      weight(j, i) = u(rng);
      V.col(k * i + j) = P.col(i) + 0.003 * Vec3(g(rng), g(rng), g(rng));
    }
    weight.col(i) /= weight.col(i).sum();
  }
  vertex(1, 0) = vertex(0, 0);
  FrictionTerm embedded(EmbeddedPoints(vertex, weight, "test", -1), kSphere, turning_pose, dhat, 1e3, 0.6, velocity);
  embedded.begin_step(flatten(V), t0, t1);
  ASSERT_EQ(embedded.lagged_points(), n);
  Eigen::Matrix3Xd Y(3, k * n);
  for (int i = 0; i < n; ++i) {
    const Vec3 slip = (i % 2 ? 0.3 : 0.02) * Vec3(g(rng), g(rng), g(rng)).normalized();
    for (int j = 0; j < k; ++j) Y.col(k * i + j) = carry * V.col(k * i + j) + slip + 0.002 * Vec3(g(rng), g(rng), g(rng));
  }
  expect_fd_and_psd(embedded, flatten(Y), "embedded");
}

TEST(FrictionTerm, NothingWithoutContactOrTimeAndBadArgumentsThrow) {
  const ColliderShape plane{Shape::plane, Vec3::Zero(), Vec3::UnitY(), 0.0};
  Eigen::Matrix3Xd X(3, 2);
  X << 0, 1, 0.5, 0.05, 0, 0;  // 0.5 above (out of range), 0.05 above (in range of d̂ = 0.1)
  FrictionTerm term(EmbeddedPoints::plain({0, 1}, "test"), plane, {}, 0.1, 1.0, 0.5, 1.0);
  term.begin_step(flatten(X), 0.0, 0.1);
  EXPECT_EQ(term.lagged_points(), 1);
  term.begin_step(flatten(X), 0.1, 0.1);  // no time passes: no slip threshold, no friction
  EXPECT_EQ(term.lagged_points(), 0);
  EXPECT_EQ(term.energy(flatten(X) + Eigen::VectorXd::Ones(6)), 0.0);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints::plain({0}, "test"), plane, {}, 0.1, 1.0, -0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints::plain({0}, "test"), plane, {}, 0.1, 1.0, NAN, 1.0), std::invalid_argument);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints::plain({0}, "test"), plane, {}, 0.1, 1.0, 0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints::plain({0}, "test"), plane, {}, 0.0, 1.0, 0.5, 1.0), std::invalid_argument);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints::plain({-1}, "test"), plane, {}, 0.1, 1.0, 0.5, 1.0), std::invalid_argument);
  EXPECT_THROW(FrictionTerm(EmbeddedPoints(Eigen::MatrixXi::Zero(2, 1), Eigen::MatrixXd::Ones(1, 1), "test", -1), plane, {}, 0.1, 1.0, 0.5, 1.0),
               std::invalid_argument);
}

struct Slide {
  Eigen::VectorXd x;      ///< the final state
  double early = 0.0;     ///< the centroid's x at t = 0.5
  double late = 0.0;      ///< at t = 1
  double base_early = 0.0, base = 0.0;  ///< the bottom face's mean x at t = ½ and 1 (0 at the start)
};

/// Backward Euler (h = 0.01) of cubes of density 100 with Lamé μ, λ = 10 μ.
SimulationSetup cube_dynamics(const VolumeMesh& m, double mu) {
  SimulationSetup setup;
  setup.mesh = m;
  setup.materials = {make_material("stable_neo_hookean", {mu, 10.0 * mu})};
  setup.density = 100.0;
  setup.integrator = Integrator::backward_euler;
  setup.dt = 0.01;
  setup.newton.tolerance = 1e-2;
  // Sticking is a stiff spring (2μλ/ε per vertex, ε = ε_v h = 1e-5: about 1e8 here), which leaves ‖g‖ at the
  // energy's rounding above 1e-2: a step rule (a tenth of a micrometre on a cube of 2) stops there.
  setup.newton.step_tolerance = 1e-7;
  setup.linear.name = "ldlt";
  return setup;
}

/// A cube [−1, 1]³ of tets resting on the plane y = −1.01 under gravity tilted by θ along x (tan θ = 1/2),
/// for 1 s of backward Euler (h = 0.01); friction μ (none: no friction term at all).
Slide slide(double mu, bool with_term) {
  const VolumeMesh m = box_tets(2);
  SimulationSetup setup = cube_dynamics(m, 2e5);
  const double theta = std::atan(0.5);
  setup.gravity = 9.8 * Vec3(std::sin(theta), -std::cos(theta), 0.0);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  std::vector<int> surface(F.data(), F.data() + F.size());
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  const double dhat = 0.02, kappa = 1e8;
  const Vec3 point(0, -1.01, 0), normal = Vec3::UnitY();
  setup.terms.push_back(std::make_shared<ShapeColliderTerm>(EmbeddedPoints::plain(surface, "test"), ColliderShape{Shape::plane, point, normal, 0.0}, ColliderPose{}, dhat, kappa));
  if (with_term)
    setup.terms.push_back(std::make_shared<FrictionTerm>(EmbeddedPoints::plain(surface, "test"), ColliderShape{Shape::plane, point, normal, 0.0}, ColliderPose{}, dhat, kappa, mu, 1e-3));
  Simulation sim(std::move(setup));
  Slide out;
  const auto centroid_x = [&] { return sim.x()(Eigen::seqN(0, m.vertex_count(), 3)).mean(); };
  std::vector<int> bottom;
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    if (m.vertices(1, v) == -1.0) bottom.push_back(static_cast<int>(v));
  const auto base_x = [&] {
    double sum = 0.0;
    for (const int v : bottom) sum += sim.x()[3 * v];
    return sum / static_cast<double>(bottom.size());
  };
  for (int s = 1; s <= 100; ++s) {
    const StepReport r = sim.step(0.01 * s);
    EXPECT_TRUE(r.converged) << "mu " << mu << " step " << s << ": " << r.failure;
    if (!r.converged) break;
    if (s == 50) {
      out.early = centroid_x();
      out.base_early = base_x();
    }
  }
  out.late = centroid_x();
  out.x = sim.x();
  out.base = base_x();
  return out;
}

TEST(FrictionTerm, ACubeOnATiltedPlaneSlidesAsCoulombSaysOrSticks) {
  const double theta = std::atan(0.5);
  // From rest with constant acceleration a, x(1) − x(½) = a (1 − ¼)/2.
  const auto acceleration = [](const Slide& s) { return (s.late - s.early) / 0.375; };
  const Slide frictionless = slide(0.0, false), zero = slide(0.0, true);
  EXPECT_TRUE(frictionless.x == zero.x);  // μ = 0: bit for bit the run without the term
  const Slide sliding = slide(0.2, true), sticking = slide(0.8, true);
  const double a0 = 9.8 * std::sin(theta), a1 = 9.8 * (std::sin(theta) - 0.2 * std::cos(theta));
  std::cout << "acceleration: frictionless " << acceleration(frictionless) << " (g sin θ " << a0 << "), μ = 0.2 "
            << acceleration(sliding) << " (" << a1 << "); μ = 0.8: its centroid moved " << sticking.late << " (from t = ½ "
            << sticking.late - sticking.early << "), its base " << sticking.base << " (from t = ½ "
            << sticking.base - sticking.base_early << ")\n";
  EXPECT_NEAR(acceleration(frictionless), a0, 0.05 * a0);
  EXPECT_NEAR(acceleration(sliding), a1, 0.05 * a1);
  // μ > tan θ: it stays. Settled (from t = ½) the base creeps slower than ε_v = 1 mm/s (while the cube first
  // bounces on the barrier, its base slips a little); the centroid moves by the cube's shear under the load
  // along the slope (a few mm) and does not slide on (sliding: 0.375 a ≈ 1 from t = ½ to 1).
  EXPECT_LT(std::abs(sticking.base - sticking.base_early), 0.5e-3);
  EXPECT_LT(std::abs(sticking.base), 0.005);
  EXPECT_LT(std::abs(sticking.late), 0.02);
  EXPECT_LT(std::abs(sticking.late - sticking.early), 0.005);
}

// ---- between self-contact pairs

/// Two cubes of box_tets(1) side by side along x, `gap` apart (faces parallel: point–triangle, point–edge,
/// point–point and mollified edge–edge pairs all appear within d̂).
VolumeMesh two_cubes(double gap) {
  const VolumeMesh one = box_tets(1);
  const Eigen::Index n = one.vertex_count();
  VolumeMesh m = one;
  m.vertices.resize(3, 2 * n);
  m.vertices.leftCols(n) = one.vertices;
  m.vertices.rightCols(n) = one.vertices.colwise() + Vec3(2.0 + gap, 0.13, -0.07);
  m.cells.resize(4, 2 * one.cells.cols());
  m.cells << one.cells, one.cells.array() + static_cast<int>(n);
  return m;
}

TEST(SelfFrictionTerm, MatchesFiniteDifferencesWhileStickingAndSliding) {
  std::mt19937_64 rng(9);
  std::normal_distribution<double> g(0.0, 1.0);
  const double dhat = 0.1, kappa = 10.0;
  const VolumeMesh m = two_cubes(0.04);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const Eigen::Index n = m.vertex_count();
  const Eigen::VectorXd xt = flatten(m.vertices);
  for (const double slide : {0.01, 0.3}) {  // ε = 0.1: sticking, sliding
    // On the volume's vertices.
    auto contact = std::make_shared<ContactTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, dhat, kappa);
    ASSERT_GT(contact->active_pairs(xt), 4);
    SelfFrictionTerm term(contact, EmbeddedPoints::every(n), dhat, kappa, 0.5, 1.0);
    term.begin_step(xt, 0.0, 0.1);
    ASSERT_GT(term.lagged_points(), 4);
    // Each pair's closest points: their gap (the anchor) is as long as a pair's distance and along its
    // normal (so the coefficients put the closest points where the distance function does). Every pair but
    // the parallel edge–edge ones (mollified to no force) is lagged.
    const std::vector<ContactPair> pairs = contact->pairs(xt);
    std::size_t forced = 0;
    for (const ContactPair& p : pairs) forced += p.kind != ContactPair::Kind::edge_edge;
    EXPECT_GE(term.slips().size(), forced);
    for (const LaggedSlip& l : term.slips()) {
      double nearest = INFINITY;
      for (const ContactPair& p : pairs) nearest = std::min(nearest, std::abs(std::sqrt(p.squared_distance) - l.anchor.norm()));
      EXPECT_LE(nearest, 1e-12);
      EXPECT_LE((l.tangent * l.anchor).norm(), 1e-12);
    }
    Eigen::Matrix3Xd X = m.vertices;
    for (Eigen::Index v = n / 2; v < n; ++v) X.col(v) += Vec3(0.0, slide, 0.5 * slide) + 0.002 * Vec3(g(rng), g(rng), g(rng));
    expect_fd_and_psd(term, flatten(X), slide < 0.1 ? "sticking" : "sliding");
    // Embedded: each surface point 0.995 of a vertex and 0.005 of the next vertex of its cube.
    const Eigen::Index half = n / 2;
    Eigen::MatrixXi vertex(2, n);
    Eigen::MatrixXd weight(2, n);
    for (Eigen::Index v = 0; v < n; ++v) {
      vertex(0, v) = static_cast<int>(v);
      vertex(1, v) = static_cast<int>((v / half) * half + (v + 1) % half);
      weight.col(v) << 0.995, 0.005;
    }
    auto embedded_contact = std::make_shared<ContactTerm>(F, EmbeddedPoints(vertex, weight, "test", m.vertices.cols()), m.vertices, dhat, kappa);
    SelfFrictionTerm embedded(embedded_contact, EmbeddedPoints(vertex, weight, "test", -1), dhat, kappa, 0.5, 1.0);
    embedded.begin_step(xt, 0.0, 0.1);
    ASSERT_GT(embedded.lagged_points(), 4);
    expect_fd_and_psd(embedded, flatten(X), slide < 0.1 ? "embedded, sticking" : "embedded, sliding");
  }
  // At the start the slips are zero: no force.
  auto contact = std::make_shared<ContactTerm>(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, dhat, kappa);
  SelfFrictionTerm term(contact, EmbeddedPoints::every(n), dhat, kappa, 0.5, 1.0);
  term.begin_step(xt, 0.0, 0.1);
  Eigen::VectorXd grad = Eigen::VectorXd::Zero(xt.size());
  term.evaluate(xt, &grad, nullptr, PsdProjection::none);
  EXPECT_LE(grad.norm(), 1e-12 * term.normal_force());
  EXPECT_THROW(SelfFrictionTerm(nullptr, EmbeddedPoints(Eigen::MatrixXi::Zero(1, 1), Eigen::MatrixXd::Ones(1, 1), "test", -1), dhat, kappa, 0.5, 1.0),
               std::invalid_argument);
}

/// Two cubes of box_tets(2) stacked (the upper 0.01 above the lower), the lower one's bottom held, self-
/// contact between them. First settled for 0.5 s under gravity g cos θ (tan θ = ½) straight down, damped;
/// then, from there, gravity tilted by θ along x (the same load across the slope, so nothing bounces), 0.6 s
/// of backward Euler without damping; friction μ between them (none: no friction term). Returns how far the
/// upper cube's centroid has moved along x from where it settled (its whole mass: m a = m g sin θ − the
/// friction on it) at t = 0.3 and 0.6 of the tilted run.
std::pair<double, double> stacked(double mu, bool with_term) {
  const VolumeMesh one = box_tets(2);
  const Eigen::Index n = one.vertex_count();
  VolumeMesh m = one;
  m.vertices.resize(3, 2 * n);
  m.vertices.leftCols(n) = one.vertices;
  m.vertices.rightCols(n) = one.vertices.colwise() + Vec3(0.0, 2.01, 0.0);
  m.cells.resize(4, 2 * one.cells.cols());
  m.cells << one.cells, one.cells.array() + static_cast<int>(n);
  const double theta = std::atan(0.5), dhat = 0.02, kappa = 1e8;
  const KinematicSet bottom = face_pins(m, 1, -1.0, {}, "bottom");  // the lower cube's base
  const Eigen::Index all = m.vertex_count();
  const auto run = [&](const Vec3& gravity, double damping, const Eigen::VectorXd& start, int steps, bool friction,
                       const std::function<void(int, const Simulation&)>& each) {
    SimulationSetup setup = cube_dynamics(m, 2e7);
    setup.gravity = gravity;
    setup.mass_damping = damping;
    setup.kinematic.push_back(bottom);
    setup.initial = start;
    auto contact = std::make_shared<ContactTerm>(boundary_triangles(m), EmbeddedPoints::every(m.vertices.cols()), m.vertices, dhat, kappa);
    setup.terms.push_back(contact);
    std::shared_ptr<SelfFrictionTerm> term;
    if (friction) {
      term = std::make_shared<SelfFrictionTerm>(contact, EmbeddedPoints::every(all), dhat, kappa, mu, 1e-3);
      setup.terms.push_back(term);
    }
    Simulation sim(std::move(setup));
    for (int s = 1; s <= steps; ++s) {
      const StepReport r = sim.step(0.01 * s);
      EXPECT_TRUE(r.converged) << "mu " << mu << " step " << s << ": " << r.failure;
      if (!r.converged) break;
      each(s, sim);
    }
    if (term) {  // the lagged normal forces add up to the upper cube's weight across the slope (7 012 N)
      EXPECT_NEAR(term->normal_force(), 800.0 * 9.8 * std::cos(theta), 0.02 * 7012.0) << "mu " << mu;
    }
    return sim.x();
  };
  const Eigen::VectorXd settled =
      run(Vec3(0.0, -9.8 * std::cos(theta), 0.0), 20.0, Eigen::Map<const Eigen::VectorXd>(m.vertices.data(), m.vertices.size()), 50,
          false, [](int, const Simulation&) {});
  const auto slip = [&](const Eigen::VectorXd& x) { return x(Eigen::seqN(3 * n, n, 3)).mean(); };  // the upper cube's centroid x
  const double at_start = slip(settled);
  double early = 0.0;
  const Eigen::VectorXd end = run(9.8 * Vec3(std::sin(theta), -std::cos(theta), 0.0), 0.0, settled, 60, with_term,
                                  [&](int s, const Simulation& sim) {
                                    if (s == 30) early = slip(sim.x()) - at_start;
                                  });
  return {early, slip(end) - at_start};
}

TEST(SelfFrictionTerm, ACubeOnAnotherOnASlopeSlidesAsCoulombSaysOrSticks) {
  const double theta = std::atan(0.5);
  // From rest with constant acceleration a: x(0.6) − x(0.3) = a (0.36 − 0.09)/2.
  const auto acceleration = [](const std::pair<double, double>& x) { return (x.second - x.first) / 0.135; };
  const auto none = stacked(0.0, false), some = stacked(0.2, true), much = stacked(1.2, true);
  const double a0 = 9.8 * std::sin(theta), a1 = 9.8 * (std::sin(theta) - 0.2 * std::cos(theta));
  std::cout << "upper cube's acceleration: frictionless " << acceleration(none) << " (" << a0 << "), μ = 0.2 " << acceleration(some)
            << " (" << a1 << "); μ = 1.2 moved " << much.second << " (from t = 0.3 " << much.second - much.first << ")\n";
  EXPECT_NEAR(acceleration(none), a0, 0.05 * a0);
  EXPECT_NEAR(acceleration(some), a1, 0.05 * a1);
  // μ = 1.2 > 2 tan θ: it sticks even under the sudden load's overshoot (an undamped elastic stack loaded at
  // once swings to twice its static shear force, more than 0.8 N can hold for a moment), moving by the two
  // cubes' shear only.
  EXPECT_LT(std::abs(much.second), 0.02);
  EXPECT_LT(std::abs(much.second - much.first), 0.02);
}

}  // namespace
}  // namespace snh
