// BDF2 beside backward Euler: its order of accuracy (errors against a fine reference as dt halves), its
// variable-step coefficients (a free fall is a parabola, integrated exactly from an exact history whatever
// the steps), a checkpoint's exact resume, and a released cantilever that keeps its vibration.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <initializer_list>
#include <iostream>

#include "snh/mesh/box.hpp"
#include "snh/sim/simulation.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::flatten;

/// A free cube of hexes, stretched and squeezed at t = 0 and let go (no gravity, no damping).
SimulationSetup free_cube(Integrator integrator, double dt) {
  SimulationSetup s;
  s.mesh = box_hexes(2);
  s.materials = {make_material("stable_neo_hookean", {1.0, 10.0})};
  s.integrator = integrator;
  s.dt = dt;
  s.initial = flatten(s.mesh.vertices);
  for (Eigen::Index v = 0; v < s.mesh.vertex_count(); ++v)
    s.initial.segment<3>(3 * v) = s.initial.segment<3>(3 * v).cwiseProduct(Eigen::Vector3d(1.3, 0.9, 1.1));
  s.linear.name = "ldlt";
  s.linear.reuse_factor = false;  // no factor kept from step to step: a restored run repeats the same arithmetic
  s.newton.tolerance = 1e-9;
  return s;
}

/// The positions at time T after steps of dt (the setup changed by `adjust` first).
Eigen::VectorXd run_to(Integrator integrator, double dt, double T, const std::function<void(SimulationSetup&)>& adjust = {}) {
  SimulationSetup s = free_cube(integrator, dt);
  if (adjust) adjust(s);
  Simulation sim(std::move(s));
  const int steps = static_cast<int>(std::lround(T / dt));
  for (int k = 1; k <= steps; ++k) {
    const StepReport r = sim.step(k * dt);
    EXPECT_TRUE(r.converged) << r.failure;
  }
  return sim.x();
}

TEST(Bdf2, IsSecondOrderWhereBackwardEulerIsFirst) {
  const double T = 0.32;
  const Eigen::VectorXd reference = run_to(Integrator::bdf2, 0.0025, T);
  double ratio[2][2];
  for (int i = 0; i < 2; ++i) {
    const Integrator integrator = i == 0 ? Integrator::backward_euler : Integrator::bdf2;
    double e[3];
    for (int k = 0; k < 3; ++k) e[k] = (run_to(integrator, 0.04 / (1 << k), T) - reference).cwiseAbs().maxCoeff();
    ratio[i][0] = e[0] / e[1];
    ratio[i][1] = e[1] / e[2];
    std::cout << integrator_name(integrator) << ": errors " << e[0] << " " << e[1] << " " << e[2] << ", ratios " << ratio[i][0] << " "
              << ratio[i][1] << "\n";
  }
  // Halving dt halves backward Euler's error and quarters BDF2's.
  for (int k = 0; k < 2; ++k) {
    EXPECT_GT(ratio[0][k], 1.6);
    EXPECT_LT(ratio[0][k], 2.5);
    EXPECT_GT(ratio[1][k], 3.3);
    EXPECT_LT(ratio[1][k], 5.0);
  }
}

/// A box in free fall: X + t u + t² g/2, at velocity u + t g.
struct FreeFall {
  Eigen::Vector3d g{0.5, -9.81, 0.2}, u{1.0, 2.0, -0.5};
  Eigen::VectorXd X = flatten(box_hexes(2).vertices);
  [[nodiscard]] Eigen::VectorXd exact(double t) const {
    Eigen::VectorXd x = X;
    for (Eigen::Index v = 0; v < X.size() / 3; ++v) x.segment<3>(3 * v) += t * u + 0.5 * t * t * g;
    return x;
  }
  [[nodiscard]] Eigen::VectorXd velocity(double t) const {
    Eigen::VectorXd v(X.size());
    for (Eigen::Index i = 0; i < X.size() / 3; ++i) v.segment<3>(3 * i) = u + t * g;
    return v;
  }
};

/// Steps of the lengths `steps` from `state` under the fall's gravity, each in a simulation of its own (a
/// simulation's steps are its dt; the state carried on, as a split step's parts do). `worst` becomes the
/// largest error of the positions and velocities after any step; where aux_size ≥ 0, every state must hold
/// that many numbers beside x.
void fall(Integrator integrator, const FreeFall& f, SimulationState& state, std::initializer_list<double> steps, double& worst,
          Eigen::Index aux_size = -1) {
  worst = 0.0;
  for (const double h : steps) {
    SimulationSetup s = free_cube(integrator, h);
    s.initial.resize(0);
    s.gravity = f.g;
    Simulation sim(std::move(s));
    sim.restore(state);
    const StepReport r = sim.step(state.time + h);
    ASSERT_TRUE(r.converged) << r.failure;
    worst = std::max(worst, (sim.x() - f.exact(sim.time())).cwiseAbs().maxCoeff());
    worst = std::max(worst, (sim.v() - f.velocity(sim.time())).cwiseAbs().maxCoeff());
    state = sim.state();
    if (aux_size >= 0) ASSERT_EQ(state.aux.size(), aux_size);
  }
}

TEST(Bdf2, VariableStepsIntegrateAFreeFallExactly) {
  // A body in free fall moves along a parabola, which BDF2's variable-step formula reproduces exactly once
  // its history is exact; backward Euler's is off by h²g/2 a step.
  const FreeFall f;
  const Eigen::Index n = f.X.size();
  for (const Integrator integrator : {Integrator::bdf2, Integrator::backward_euler}) {
    // At t = 0 after a step of 0.01 from t = −0.01: positions, velocity, and the history before.
    SimulationState state{.x = f.exact(0.0), .aux = f.velocity(0.0), .time = 0.0, .steps = 1};
    if (integrator == Integrator::bdf2) {
      state.aux.resize(3 * n + 1);
      state.aux << f.velocity(0.0), f.exact(-0.01), f.velocity(-0.01), 0.01;
    }
    double worst = 0.0;
    fall(integrator, f, state, {0.01, 0.015, 0.02, 0.01, 0.005, 0.01, 0.01}, worst);  // ratios ½ to 2
    if (integrator == Integrator::bdf2) {
      EXPECT_LT(worst, 1e-11) << "BDF2 is exact on a parabola";
    }
    else EXPECT_GT(worst, 1e-4) << "backward Euler is not";
  }
}

TEST(Bdf2, ResumesBitForBit) {
  Simulation whole(free_cube(Integrator::bdf2, 0.02));
  SimulationState saved;
  for (int k = 1; k <= 12; ++k) {
    ASSERT_TRUE(whole.step(0.02 * k).converged);
    if (k == 5) saved = whole.state();
  }
  ASSERT_EQ(saved.aux.size(), 3 * saved.x.size() + 1) << "the state holds BDF2's history";
  Simulation resumed(free_cube(Integrator::bdf2, 0.02));
  resumed.restore(saved);
  for (int k = 6; k <= 12; ++k) ASSERT_TRUE(resumed.step(0.02 * k).converged);
  EXPECT_EQ((resumed.x() - whole.x()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((resumed.v() - whole.v()).cwiseAbs().maxCoeff(), 0.0);
  // A state without a history (backward Euler's) starts BDF2 again with a backward Euler step; a history
  // with no last step length is refused.
  SimulationState bad = saved;
  bad.aux[bad.aux.size() - 1] = 0.0;
  EXPECT_THROW(resumed.restore(bad), std::invalid_argument);
  resumed.restore({.x = saved.x, .aux = saved.aux.head(saved.x.size()), .time = saved.time, .steps = saved.steps});
  EXPECT_EQ(resumed.state().aux.size(), saved.x.size());
}

TEST(Bdf2, AStepThatFailsInEveryHalfEndsAsTheWholeStepDid) {
  // One Newton iteration cannot reach 1e-9 here, in a whole step or in any part. After halving, the state
  // is the whole step's last iterate at its time (as with no halving: a run going on from it, with
  // --keep-going, keeps its clock), and the failure says how the step was retried.
  SimulationState after[2];
  StepReport reports[2];
  for (const int halvings : {0, 2}) {
    SimulationSetup s = free_cube(Integrator::bdf2, 0.02);
    s.newton.max_iterations = 1;
    s.step_halvings = halvings;
    Simulation sim(std::move(s));
    const int i = halvings == 0 ? 0 : 1;
    reports[i] = sim.step(0.02);
    after[i] = sim.state();
    EXPECT_EQ(sim.time(), 0.02);
  }
  ASSERT_FALSE(reports[0].converged);
  ASSERT_FALSE(reports[1].converged);
  EXPECT_EQ(reports[1].halvings, 2);  // the whole step, then its first half; the first quarter fails
  EXPECT_NE(reports[1].failure.find("(the step was retried in halves 2 times, down to dt / 4)"), std::string::npos)
      << reports[1].failure;
  EXPECT_EQ(reports[1].newton.iterations, 3);
  EXPECT_EQ((after[1].x - after[0].x).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((after[1].aux - after[0].aux).cwiseAbs().maxCoeff(), 0.0);
}

/// A bar [0, 2] × [−0.1, 0.1]² of 20 × 2 × 2 cubic hexes (the corner order of box_hexes).
VolumeMesh bar() {
  const int nx = 20, n = 2;
  const VolumeMesh unit = box_hexes(1);
  VolumeMesh m;
  m.type = CellType::hex8;
  m.vertices.resize(3, (nx + 1) * (n + 1) * (n + 1));
  const auto index = [&](int i, int j, int k) { return i + (nx + 1) * (j + (n + 1) * k); };
  for (int k = 0; k <= n; ++k)
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= nx; ++i) m.vertices.col(index(i, j, k)) = Eigen::Vector3d(0.1 * i, 0.1 * j - 0.1, 0.1 * k - 0.1);
  m.cells.resize(8, nx * n * n);
  int c = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < nx; ++i, ++c)
        for (int a = 0; a < 8; ++a) {
          const Eigen::Vector3d corner = unit.vertices.col(unit.cells(a, 0));  // ±1
          m.cells(a, c) = index(i + (corner.x() > 0), j + (corner.y() > 0), k + (corner.z() > 0));
        }
  return m;
}

/// The bar, clamped at x = 0.
SimulationSetup cantilever(Integrator integrator, double dt) {
  SimulationSetup s;
  s.mesh = bar();
  s.materials = {make_material("stable_neo_hookean", {300.0, 1200.0})};
  s.integrator = integrator;
  s.dt = dt;
  KinematicSet clamp{.name = "clamp", .vertices = {}, .provider = {}};
  for (Eigen::Index v = 0; v < s.mesh.vertex_count(); ++v)
    if (s.mesh.vertices(0, v) == 0.0) clamp.vertices.push_back(static_cast<int>(v));
  clamp.provider = std::make_shared<ScriptedMotion>(s.mesh.vertices(Eigen::all, clamp.vertices), std::vector<Motion>{});
  s.kinematic = {clamp};
  s.linear.name = "ldlt";
  s.newton.tolerance = 1e-9;
  return s;
}

TEST(Bdf2, AReleasedCantileverKeepsMoreOfItsVibration) {
  // Bent by a small load and released, undamped: its tip should swing back and forth at its first
  // amplitude. Over five periods (about 4 s each here) at 20 steps a period, backward Euler loses nearly all
  // of it; BDF2 most of it stays (bench/cantilever.py measures the same bar).
  SimulationSetup bend = cantilever(Integrator::quasi_static, 0.0);
  bend.gravity = Eigen::Vector3d(0, -0.3, 0);
  Simulation statics(std::move(bend));
  ASSERT_TRUE(statics.step(1.0).converged);
  const Eigen::VectorXd bent = statics.x();
  Eigen::Index tip = 0;
  for (Eigen::Index v = 0; v < bent.size() / 3; ++v)
    if (statics.mesh().vertices.col(v).cwiseAbs().isApprox(Eigen::Vector3d(2, 0, 0), 1e-12)) tip = v;
  const double y0 = bent[3 * tip + 1];
  ASSERT_LT(y0, -0.1) << "the tip is bent down";
  double kept[3];
  for (int i = 0; i < 3; ++i) {
    const Integrator integrator = i == 0 ? Integrator::backward_euler : i == 1 ? Integrator::bdf2 : Integrator::tr_bdf2;
    SimulationSetup s = cantilever(integrator, 0.2);
    s.initial = bent;
    Simulation sim(std::move(s));
    double swing = 0.0, highest = 0.0;
    for (int k = 1; k <= 100; ++k) {
      ASSERT_TRUE(sim.step(0.2 * k).converged) << integrator_name(integrator) << " step " << k;
      const double y = sim.x()[3 * tip + 1];
      highest = std::max(highest, y);
      if (k > 80) swing = std::max(swing, std::abs(y));  // the fifth period
    }
    kept[i] = swing / std::abs(y0);
    std::cout << integrator_name(integrator) << ": amplitude kept in the fifth period " << kept[i] << "\n";
    EXPECT_GT(highest, 0.5 * std::abs(y0)) << integrator_name(integrator) << ": the tip swings up past the axis";
  }
  EXPECT_LT(kept[0], 0.1) << "backward Euler damps the vibration away";
  EXPECT_GT(kept[1], 0.7) << "BDF2 keeps most of it";
  EXPECT_GT(kept[2], kept[1]) << "TR-BDF2 keeps more than BDF2";
}

TEST(TrBdf2, IsSecondOrderWithDampingAndGravity) {
  // The vibrating cube of IsSecondOrderWhereBackwardEulerIsFirst with gravity and mass damping, which the
  // trapezoidal stage takes at v_n and v_γ: a damping force taken at the wrong velocity would make it first
  // order, or converge to another motion. A fine BDF2 run (its own treatment of damping) agrees with TR-BDF2's
  // reference. Stiffness damping's K is the elastic Hessian at the step's start, as for backward Euler and
  // BDF2: its lag costs TR-BDF2 its second order (halving dt then divides the error by about 2.5), though
  // the error stays far below BDF2's. (The references' dt is 0.0025: at 0.00125, m/η² is large enough that
  // ‖g‖ cannot fall below the test's 1e-9 in the rounding of the positions.)
  for (const double beta : {0.0, 0.01}) {
    const auto damped = [beta](SimulationSetup& s) {
      s.gravity = Eigen::Vector3d(0.3, -2.0, 0.1);
      s.mass_damping = 0.5;
      s.stiffness_damping = beta;
    };
    const double T = 0.32;
    const Eigen::VectorXd reference = run_to(Integrator::tr_bdf2, 0.0025, T, damped);
    double e[3], b[3];
    for (int k = 0; k < 3; ++k) {
      e[k] = (run_to(Integrator::tr_bdf2, 0.04 / (1 << k), T, damped) - reference).cwiseAbs().maxCoeff();
      b[k] = (run_to(Integrator::bdf2, 0.04 / (1 << k), T, damped) - reference).cwiseAbs().maxCoeff();
    }
    const double fine_bdf2 = (run_to(Integrator::bdf2, 0.000625, T, damped) - reference).cwiseAbs().maxCoeff();
    std::cout << "beta " << beta << ": tr_bdf2 errors " << e[0] << " " << e[1] << " " << e[2] << ", ratios " << e[0] / e[1] << " "
              << e[1] / e[2] << "; bdf2 errors " << b[0] << " " << b[1] << " " << b[2] << "; BDF2 at dt 0.000625 differs by "
              << fine_bdf2 << "\n";
    for (int k = 0; k < 2; ++k) {
      EXPECT_GT(e[k] / e[k + 1], beta == 0.0 ? 3.3 : 1.8) << "beta " << beta;
      EXPECT_LT(e[k] / e[k + 1], 5.5) << "beta " << beta;
      EXPECT_LT(e[k], 0.2 * b[k]) << "beta " << beta << ": TR-BDF2's error is smaller than BDF2's at the same dt";
    }
    EXPECT_LT(fine_bdf2, 0.1 * e[0]) << "beta " << beta;
  }
}

TEST(TrBdf2, IntegratesAFreeFallExactlyFromRest) {
  // The trapezoidal rule and BDF2 are both exact on a parabola, and TR-BDF2 needs no history: from a state of
  // positions and velocity alone, through steps of any length, a free fall stays on its parabola.
  const FreeFall f;
  SimulationState state{.x = f.exact(0.0), .aux = f.velocity(0.0), .time = 0.0, .steps = 0};
  double worst = 0.0;
  fall(Integrator::tr_bdf2, f, state, {0.01, 0.015, 0.04, 0.01, 0.005, 0.02}, worst, f.X.size());  // x and v alone
  EXPECT_LT(worst, 1e-11);
}

TEST(TrBdf2, ResumesBitForBitAndFailsOnTheStepsClock) {
  Simulation whole(free_cube(Integrator::tr_bdf2, 0.02));
  SimulationState saved;
  for (int k = 1; k <= 12; ++k) {
    const StepReport r = whole.step(0.02 * k);
    ASSERT_TRUE(r.converged);
    EXPECT_EQ(r.substeps, 1);
    EXPECT_GE(r.newton.iterations, 2) << "two solves a step";
    if (k == 5) saved = whole.state();
  }
  EXPECT_EQ(whole.steps(), 12) << "a step of two solves counts once, as a resumed run counts it";
  Simulation resumed(free_cube(Integrator::tr_bdf2, 0.02));
  resumed.restore(saved);
  for (int k = 6; k <= 12; ++k) ASSERT_TRUE(resumed.step(0.02 * k).converged);
  EXPECT_EQ((resumed.x() - whole.x()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ((resumed.v() - whole.v()).cwiseAbs().maxCoeff(), 0.0);

  // A first stage that cannot converge fails the step at the step's time, saying which stage it was.
  SimulationSetup s = free_cube(Integrator::tr_bdf2, 0.02);
  s.newton.max_iterations = 1;
  s.step_halvings = 0;
  Simulation failing(std::move(s));
  const StepReport r = failing.step(0.02);
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.failed_time, 0.02);
  EXPECT_EQ(failing.time(), 0.02);
  EXPECT_EQ(r.failure.rfind("TR-BDF2's first stage: no convergence in 1 Newton iterations", 0), 0u) << r.failure;
}

}  // namespace
}  // namespace snh
