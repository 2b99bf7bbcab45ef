// Time stepping: the incremental potential's derivatives (finite differences), lumped masses, that
// backward Euler never gains energy without forcing, that damping dissipates, and that a pinned bar under
// gravity comes to rest at the quasi-static solution.
#include <gtest/gtest.h>

#include <iostream>
#include <random>
#include <sstream>

#include "snh/fem/problem.hpp"
#include "snh/mesh/box.hpp"
#include "fem/problem_fd.hpp"
#include "snh/sim/dynamics.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/solve/newton.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::flatten;

TEST(Dynamics, LumpedMassSumsToDensityTimesVolume) {
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const VolumeMesh m = type == CellType::tet4 ? box_tets(3) : box_hexes(3);
    const ElasticTerm elastic(m, make_material("stable_neo_hookean", {1, 10}));
    const Eigen::VectorXd mass = lumped_mass(elastic, 2.5);
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(mass(Eigen::seqN(a, m.vertex_count(), 3)).sum(), 2.5 * 8.0, 1e-12);
    EXPECT_GT(mass.minCoeff(), 0.0);
  }
  const ElasticTerm elastic(box_hexes(1), make_material("stable_neo_hookean", {1, 10}));
  EXPECT_THROW((void)lumped_mass(elastic, 0.0), std::invalid_argument);
}

/// The elastic and time-step terms of a step in one problem.
struct Step {
  Step(const VolumeMesh& m, const std::vector<std::uint8_t>& fixed, const StepTerms& terms, double density)
      : elastic(m, make_material("stable_neo_hookean", {1.0, 10.0})),
        dofs(fixed),
        inertia(elastic, dofs, lumped_mass(elastic, density), terms),
        problem(dofs) {
    problem.add(elastic);
    problem.add(inertia);
  }
  ElasticTerm elastic;
  DofMap dofs;
  TimeStepTerm inertia;
  Problem problem;
};

TEST(Dynamics, IncrementalPotentialMatchesFiniteDifferences) {
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const VolumeMesh m = type == CellType::tet4 ? box_tets(2) : box_hexes(2);
    std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
    for (int d = 0; d < 6; ++d) fixed[d] = 1;
    Step step(m, fixed, {.dt = 0.05, .gravity = Eigen::Vector3d(0.3, -9.8, 1.0), .mass_damping = 0.7, .stiffness_damping = 0.02},
              3.0);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> n(0.0, 0.05);
    Eigen::VectorXd x_n = flatten(m.vertices), v_n(x_n.size()), x(x_n.size());
    for (Eigen::Index i = 0; i < x_n.size(); ++i) {
      x_n[i] = 1.05 * x_n[i] + n(rng);
      v_n[i] = 10 * n(rng);
      x[i] = x_n[i] + n(rng);  // the kinematic DOFs move too: stiffness damping couples them to the free ones
    }
    step.inertia.begin_step(x_n, v_n);
    Eigen::VectorXd g;
    EXPECT_DOUBLE_EQ(step.problem.energy(x), step.problem.evaluate(x, g, nullptr, PsdProjection::none));
    const FdErrors e = problem_fd_errors(step.problem, x);
    EXPECT_LE(e.gradient, 1e-8);
    EXPECT_LE(e.hessian, 1e-8);
  }
}

TEST(Dynamics, StiffnessDampingLeavesARigidlyCarriedBodyAlone) {
  // A cube moving at velocity u, its x = ±1 faces carried by kinematic DOFs at the same velocity: one
  // backward-Euler step with stiffness damping only must translate it rigidly (no elastic force, no
  // inertial force, and K_n Δ = 0 for a uniform Δ). Damping only the free DOFs' motion relative to each
  // other (K_ff Δ_f) would hold the free vertices back.
  const VolumeMesh m = box_hexes(3);
  std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    if (std::abs(std::abs(m.vertices(0, v)) - 1.0) < 1e-12) fixed[3 * v] = fixed[3 * v + 1] = fixed[3 * v + 2] = 1;
  const double h = 0.01;
  Step step(m, fixed, {.dt = h, .stiffness_damping = 0.5}, 1.0);
  const Eigen::Vector3d u(0.5, 0.2, -0.1);
  const Eigen::VectorXd x_n = flatten(m.vertices);
  Eigen::VectorXd v_n(x_n.size());
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) v_n.segment<3>(3 * v) = u;
  const Eigen::VectorXd target = x_n + h * v_n;
  step.inertia.begin_step(x_n, v_n);
  // Start away from the answer: the free vertices where they were, the kinematic ones at their new place.
  Eigen::VectorXd x = x_n;
  for (Eigen::Index d = 0; d < x.size(); ++d)
    if (fixed[d]) x[d] = target[d];
  auto solver = make_linear_solver({.name = "ldlt"});
  const NewtonReport r = newton_solve(step.problem, x, *solver, {.tolerance = 1e-12});
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_LE((x - target).cwiseAbs().maxCoeff(), 1e-12) << "the body moved rigidly with its carriers";
  // And the damping force at the rigidly moved state is zero.
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  Step damping_only(m, fixed, {.dt = h, .stiffness_damping = 0.5}, 1.0);
  damping_only.inertia.begin_step(x_n, v_n);
  (void)damping_only.inertia.evaluate(target, &g, nullptr, PsdProjection::clamp);
  // g holds the inertia gradient (zero at the predicted state) plus the damping force β/h K_n Δ.
  EXPECT_LE(g.cwiseAbs().maxCoeff(), 1e-12);
}

/// A scene in memory, run quietly into a temporary directory.
SceneResult run_quietly(Scene s, const std::string& name) {
  s.output.dir = std::filesystem::temp_directory_path() / ("snh_test_dyn_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(s.output.dir);
  std::ostringstream log;
  SceneResult r = run_scene(s, log);
  std::filesystem::remove_all(s.output.dir);
  return r;
}

Scene free_cube(const std::string& material) {
  Scene s;
  s.source = "free_cube";
  s.mesh.element = CellType::hex8;
  s.mesh.resolution = 3;
  s.material.name = material;
  s.material.params = {1.0, 10.0};
  s.time.dt = 0.02;
  s.time.end_time = 2.0;
  s.time.frames = 40;
  s.initial.push_back(ScaleOp{.factors = Eigen::Vector3d(1.3, 0.9, 1.1)});
  s.output.vtu = false;
  return s;
}

TEST(Dynamics, BackwardEulerNeverGainsEnergyWithoutForcing) {
  for (const char* material : {"stable_neo_hookean", "neo_hookean", "corotated"}) {
    const SceneResult r = run_quietly(free_cube(material), material);
    ASSERT_TRUE(r.all_converged) << material << ": " << r.failure;
    ASSERT_EQ(r.frames.size(), 41u);
    for (std::size_t f = 1; f < r.frames.size(); ++f)
      EXPECT_LE(r.frames[f].total_energy, r.frames[f - 1].total_energy + 1e-9) << material << " frame " << f;
    // It moves (kinetic energy appears) and dissipates part of its starting energy, but not all at once.
    double peak_kinetic = 0.0;
    for (const auto& f : r.frames) peak_kinetic = std::max(peak_kinetic, f.kinetic_energy);
    EXPECT_GT(peak_kinetic, 0.05 * r.frames[0].total_energy) << material;
    EXPECT_LT(r.frames.back().total_energy, r.frames[0].total_energy) << material;
  }
}

TEST(Dynamics, DampingDissipatesFaster) {
  Scene plain = free_cube("stable_neo_hookean"), damped = plain;
  damped.forces.mass_damping = 2.0;
  damped.forces.stiffness_damping = 0.05;
  const SceneResult a = run_quietly(plain, "plain"), b = run_quietly(damped, "damped");
  ASSERT_TRUE(a.all_converged && b.all_converged);
  EXPECT_LT(b.frames.back().total_energy, 0.5 * a.frames.back().total_energy);
  // The free cube comes to rest at its rest volume (stable Neo-Hookean: rest stable).
  EXPECT_NEAR(b.frames.back().volume_ratio, 1.0, 1e-3);
}

/// A bar pinned at one end, falling under gravity (the hanging bar of scenes/, coarser).
Scene falling_bar(double density, double youngs, double dt, int frames) {
  Scene s;
  s.source = "falling_bar";
  s.mesh.element = CellType::hex8;
  s.mesh.resolution = 3;
  s.mesh.min = Eigen::Vector3d(0, -0.25, -0.25);
  s.mesh.max = Eigen::Vector3d(2, 0.25, 0.25);
  s.material.params = lame_from_youngs(youngs, 0.45);
  s.material.density = density;
  s.forces.gravity = Eigen::Vector3d(0, -9.81, 0);
  PinSpec end;
  end.select.region = Eigen::AlignedBox3d(Eigen::Vector3d(0, -1, -1), Eigen::Vector3d(0, 1, 1));
  s.pins.push_back(end);
  s.time.dt = dt;
  s.time.end_time = frames * 5 * dt;
  s.time.frames = frames;
  s.output.vtu = false;
  return s;
}

int fewest_newton_iterations(const SceneResult& r) {
  int fewest = 1 << 30;
  for (std::size_t f = 1; f < r.frames.size(); ++f) fewest = std::min(fewest, r.frames[f].newton_iterations);
  return fewest;
}

TEST(Dynamics, NewtonStopsAtTheSameStateInAnyUnits) {
  // Density and Young's modulus scaled together leave the motion unchanged (E/rho is what counts): the
  // scale-aware stopping rule must find the same positions. An absolute |g| < 1e-6 (the paper programs'
  // rule, which scenes used) took the scaled-down bar for converged at rest: it never fell.
  const SceneResult unit = run_quietly(falling_bar(1.0, 1000.0, 0.01, 4), "units_1");
  ASSERT_TRUE(unit.all_converged) << unit.failure;
  const double fall = (unit.final_positions - flatten(scene_body(falling_bar(1, 1000, 0.01, 4))->mesh.vertices)).cwiseAbs().maxCoeff();
  EXPECT_GT(fall, 0.01);
  for (double scale : {1e-6, 1e6}) {
    const SceneResult r = run_quietly(falling_bar(scale, 1000.0 * scale, 0.01, 4), "units_scaled");
    ASSERT_TRUE(r.all_converged) << scale << ": " << r.failure;
    EXPECT_GE(fewest_newton_iterations(r), 1) << scale;
    EXPECT_LT((r.final_positions - unit.final_positions).cwiseAbs().maxCoeff(), 1e-9 * fall) << scale;
  }
  Scene absolute = falling_bar(1e-6, 1e-3, 0.01, 4);
  absolute.solver.tolerance = 1e-6;
  absolute.solver.newton.relative_step_tolerance = 0.0;
  const SceneResult stuck = run_quietly(absolute, "units_absolute");
  EXPECT_EQ(fewest_newton_iterations(stuck), 0) << "the absolute rule, asked for, is the user's";
  EXPECT_GT((stuck.final_positions - unit.final_positions).cwiseAbs().maxCoeff(), 0.5 * fall);
}

TEST(Dynamics, TinyTimeStepsConvergeWhereRoundingBoundsTheResidual) {
  // Water-dense soft flesh at dt = 1e-5: the inertia term's rounding keeps |g| near 1e-6, so an absolute
  // |g| < 1e-6 failed after 50 Newton iterations. The relative step rule stops there, and a step rule on
  // a fixed length would stop before the first step and lose gravity's h² g (1e-10 at dt = 1e-5): the
  // bar must fall as backward Euler says, n(n+1)/2 h² g after n steps, while no wave has reached its end.
  for (double dt : {1e-4, 1e-5, 1e-6, 1e-7}) {
    const SceneResult r = run_quietly(falling_bar(1000.0, 1e5, dt, 3), "tiny_dt");
    ASSERT_TRUE(r.all_converged) << dt << ": " << r.failure;
    for (std::size_t f = 1; f < r.frames.size(); ++f) EXPECT_LE(r.frames[f].newton_iterations, 5 * 10) << dt;
    const double n = 3 * 5, fall = 0.5 * n * (n + 1) * dt * dt * 9.81;
    const Eigen::VectorXd X = flatten(scene_body(falling_bar(1000, 1e5, dt, 3))->mesh.vertices);
    double drop = 0.0;  // the largest drop in y
    for (Eigen::Index i = 1; i < X.size(); i += 3) drop = std::max(drop, X(i) - r.final_positions(i));
    EXPECT_NEAR(drop, fall, 1e-3 * fall) << dt;
  }
}

TEST(Dynamics, PinnedBarUnderGravitySettlesAtTheQuasiStaticSolution) {
  Scene s;
  s.source = "bar";
  s.mesh.element = CellType::hex8;
  s.mesh.resolution = 3;
  s.mesh.min = Eigen::Vector3d(0, -0.25, -0.25);
  s.mesh.max = Eigen::Vector3d(2, 0.25, 0.25);
  s.material.params = {300.0, 1200.0};
  s.material.density = 1.0;
  s.forces.gravity = Eigen::Vector3d(0, -9.81, 0);
  PinSpec end;
  end.select.region = Eigen::AlignedBox3d(Eigen::Vector3d(0, -1, -1), Eigen::Vector3d(0, 1, 1));
  s.pins.push_back(end);
  s.output.vtu = false;
  s.solver.tolerance = 1e-8;
  Scene statics = s;
  statics.time.integrator = Integrator::quasi_static;
  statics.time.frames = 1;
  Scene dynamics = s;
  dynamics.time.dt = 0.02;
  dynamics.time.end_time = 8.0;
  dynamics.time.frames = 40;
  dynamics.forces.mass_damping = 4.0;
  const SceneResult a = run_quietly(statics, "static"), b = run_quietly(dynamics, "dynamic");
  ASSERT_TRUE(a.all_converged) << a.failure;
  ASSERT_TRUE(b.all_converged) << b.failure;
  const double sag = (a.final_positions - flatten(scene_body(s)->mesh.vertices)).cwiseAbs().maxCoeff();
  EXPECT_GT(sag, 0.05) << "the bar bends under gravity";
  std::cout << "bar: sag " << sag << ", dynamic vs static " << (b.final_positions - a.final_positions).cwiseAbs().maxCoeff() << ", kinetic " << b.frames.back().kinetic_energy << "\n";
  EXPECT_LT((b.final_positions - a.final_positions).cwiseAbs().maxCoeff(), 1e-5 * sag)
      << "the damped motion settles where the quasi-static solve puts it";
  EXPECT_LT(b.frames.back().kinetic_energy, 1e-8);
}

}  // namespace
}  // namespace snh
