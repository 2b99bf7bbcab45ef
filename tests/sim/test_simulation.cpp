// The stepping core without files: a Simulation driven by kinematic providers (a Python script or a rig
// sets targets the same way), its substeps, quadratic extrapolation and its saved state, an interruption
// that restores the frame's start, the DOF
// conflicts it refuses; scripted motions; the stats tables (one description drives JSON, CSV and resume);
// and the statuses the driver writes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "snh/mesh/box.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/sim/simulation.hpp"
#include "snh/run/stats.hpp"
#include "snh/setup/stretch.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// Targets given point by point by the caller, as a script would set them before each step.
class Scripted final : public KinematicProvider {
 public:
  explicit Scripted(Eigen::Matrix3Xd rest) : rest_(std::move(rest)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    out = rest_;
    out.row(1).array() += 0.2 * t;  // rises by 0.2 per unit time
    ++calls;
  }
  mutable int calls = 0;

 private:
  Eigen::Matrix3Xd rest_;
};

/// A hex box whose bottom layer (y = −1) is held and top layer (y = 1) follows a Scripted provider.
SimulationSetup pulled_box(Integrator integrator, std::shared_ptr<Scripted>* top_out = nullptr) {
  SimulationSetup s;
  s.mesh = box_hexes(2);
  s.materials = {make_material("stable_neo_hookean", {1.0, 10.0})};
  s.integrator = integrator;
  s.dt = 0.1;
  KinematicSet bottom{.name = "bottom"}, top{.name = "top"};
  for (Eigen::Index v = 0; v < s.mesh.vertex_count(); ++v) {
    if (s.mesh.vertices(1, v) == -1.0) bottom.vertices.push_back(static_cast<int>(v));
    if (s.mesh.vertices(1, v) == 1.0) top.vertices.push_back(static_cast<int>(v));
  }
  bottom.provider = std::make_shared<ScriptedMotion>(s.mesh.vertices(Eigen::all, bottom.vertices), std::vector<Motion>{});
  auto script = std::make_shared<Scripted>(s.mesh.vertices(Eigen::all, top.vertices));
  top.provider = script;
  if (top_out) *top_out = script;
  s.kinematic = {bottom, top};
  s.linear.name = "ldlt";
  s.newton.tolerance = 1e-10;
  return s;
}

TEST(Simulation, StepsQuasiStaticallyToTheProvidersTargets) {
  std::shared_ptr<Scripted> script;
  Simulation sim(pulled_box(Integrator::quasi_static, &script));
  EXPECT_EQ(sim.steps(), 0);
  for (int k = 1; k <= 3; ++k) {
    const StepReport r = sim.step(0.5 * k);
    ASSERT_TRUE(r.converged) << r.failure;
    EXPECT_EQ(sim.steps(), k);
    EXPECT_EQ(sim.time(), 0.5 * k);
  }
  // The top layer is where the script put it at t = 1.5; the body stretched in y only on average.
  for (Eigen::Index v = 0; v < sim.mesh().vertex_count(); ++v)
    if (sim.mesh().vertices(1, v) == 1.0) {
      EXPECT_EQ(sim.x()[3 * v + 1], 1.0 + 0.2 * 1.5);
    }
  EXPECT_EQ(script->calls, 3) << "the provider is asked once per step";
  const std::vector<bool> k = sim.kinematic_vertices();
  EXPECT_EQ(std::count(k.begin(), k.end(), true), 18);
}

TEST(Simulation, AFrameOfSubstepsEqualsTheSameStepsOneByOne) {
  Simulation a(pulled_box(Integrator::backward_euler)), b(pulled_box(Integrator::backward_euler));
  const StepReport frame = a.advance(0.0, 0.1, 4);
  ASSERT_TRUE(frame.converged);
  EXPECT_EQ(frame.substeps, 4);
  int newton = 0;
  for (int k = 1; k <= 4; ++k) {
    const StepReport r = b.step(0.1 * k);
    ASSERT_TRUE(r.converged);
    newton += r.newton.iterations;
  }
  EXPECT_EQ(a.x(), b.x());
  EXPECT_EQ(a.v(), b.v());
  EXPECT_EQ(frame.newton.iterations, newton);
  EXPECT_EQ(a.steps(), 4);
}

TEST(Simulation, AnInterruptedFrameReturnsToItsStart) {
  Simulation sim(pulled_box(Integrator::backward_euler));
  ASSERT_TRUE(sim.advance(0.0, 0.1, 2).converged);
  const SimulationState before = sim.state();
  NewtonOptions newton = sim.setup().newton;
  int calls = 0;
  newton.should_stop = [&] { return ++calls > 3; };  // stops inside the second substep
  const StepReport r = sim.advance(0.2, 0.1, 3, &newton);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(sim.x(), before.x);
  EXPECT_EQ(sim.v(), before.aux);
  EXPECT_EQ(sim.time(), before.time);
  EXPECT_EQ(sim.steps(), before.steps);
}

/// Targets that rise faster and faster (0.15 t²): consecutive solutions lie on a curve.
class Accelerating final : public KinematicProvider {
 public:
  explicit Accelerating(Eigen::Matrix3Xd rest) : rest_(std::move(rest)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    out = rest_;
    out.row(1).array() += 0.15 * t * t;
  }

 private:
  Eigen::Matrix3Xd rest_;
};

SimulationSetup accelerating_box(int extrapolation) {
  SimulationSetup s = pulled_box(Integrator::quasi_static);
  s.kinematic[1].provider = std::make_shared<Accelerating>(s.mesh.vertices(Eigen::all, s.kinematic[1].vertices));
  s.extrapolation = extrapolation;
  s.linear.reuse_factor = false;  // every solve from a fresh factor: a restored run matches bit for bit
  return s;
}

TEST(Simulation, QuadraticExtrapolationStartsCloserAndResumesExactly) {
  Simulation linear(accelerating_box(1)), quadratic(accelerating_box(2));
  // From the third step on the guess is closer: the first residual of each solve is smaller.
  for (int k = 1; k <= 6; ++k) {
    const StepReport a = linear.step(0.4 * k), b = quadratic.step(0.4 * k);
    ASSERT_TRUE(a.converged && b.converged) << a.failure << b.failure;
    if (k < 3) {
      EXPECT_EQ(a.newton.residuals, b.newton.residuals) << "the linear guess until three solutions exist";
    }
    else EXPECT_LT(b.newton.residuals.front(), 0.5 * a.newton.residuals.front()) << "step " << k;
  }
  EXPECT_LE((linear.x() - quadratic.x()).lpNorm<Eigen::Infinity>(), 1e-8) << "the same answers";
  // The state holds the last two solutions (6 #V numbers); a simulation restored from it continues exactly
  // as the one it was taken from.
  const SimulationState saved = quadratic.state();
  EXPECT_EQ(saved.aux.size(), 2 * saved.x.size());
  EXPECT_EQ(linear.state().aux.size(), saved.x.size());
  Simulation resumed(accelerating_box(2));
  resumed.restore(saved);
  for (int k = 7; k <= 8; ++k) {
    ASSERT_TRUE(quadratic.step(0.4 * k).converged);
    ASSERT_TRUE(resumed.step(0.4 * k).converged);
  }
  EXPECT_EQ(resumed.x(), quadratic.x());
  // A state of one previous solution (a checkpoint of an extrapolation-1 run) restores too.
  Simulation from_linear(accelerating_box(2));
  from_linear.restore(linear.state());
  const StepReport after = from_linear.step(0.4 * 7);
  EXPECT_TRUE(after.converged) << after.failure;
  SimulationState bad = saved;
  bad.aux.conservativeResize(bad.aux.size() - 1);
  EXPECT_THROW(resumed.restore(bad), std::invalid_argument);
}

/// The box's two end layers held stretched by 0.3 in y and turned together about the z axis by θ(t) = 0.3 t²
/// (an accelerating turn: neither extrapolation follows it exactly).
double turn(double t) { return 0.3 * t * t; }
class Turning final : public KinematicProvider {
 public:
  explicit Turning(Eigen::Matrix3Xd rest) : rest_(std::move(rest)) {
    for (Eigen::Index i = 0; i < rest_.cols(); ++i) rest_(1, i) *= 1.15;
  }
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    out = Eigen::AngleAxisd(turn(t), Eigen::Vector3d::UnitZ()).toRotationMatrix() * rest_;
  }

 private:
  Eigen::Matrix3Xd rest_;
};

SimulationSetup turning_box(bool carrier) {
  SimulationSetup s = pulled_box(Integrator::quasi_static);
  std::vector<int> ends = s.kinematic[0].vertices;
  ends.insert(ends.end(), s.kinematic[1].vertices.begin(), s.kinematic[1].vertices.end());
  s.kinematic = {KinematicSet{.name = "ends", .vertices = ends}};
  s.kinematic[0].provider = std::make_shared<Turning>(s.mesh.vertices(Eigen::all, ends));
  s.extrapolation = 2;
  const Eigen::Index n = s.mesh.vertex_count();
  if (carrier)
    s.carrier = [n](double t, std::vector<Eigen::Matrix<double, 3, 4>>& frames) {
      Eigen::Matrix<double, 3, 4> f = Eigen::Matrix<double, 3, 4>::Zero();
      f.leftCols<3>() = Eigen::AngleAxisd(turn(t), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      frames.assign(static_cast<std::size_t>(n), f);
    };
  return s;
}

TEST(Simulation, ACarrierFollowsTheMotionItDescribes) {
  // The body turns rigidly once stretched: in the carrier's frames the solution stands still, so from the
  // second step on the carried guess is the answer (to rounding), where both extrapolations miss the turn.
  Simulation plain(turning_box(false)), carried(turning_box(true));
  for (int k = 1; k <= 6; ++k) {
    const StepReport a = plain.step(0.25 * k), b = carried.step(0.25 * k);
    ASSERT_TRUE(a.converged && b.converged) << a.failure << b.failure;
    if (k >= 2) {
      EXPECT_GT(a.newton.residuals.front(), 1e-4) << "step " << k;
      EXPECT_LT(b.newton.residuals.front(), 1e-9) << "step " << k;
      EXPECT_LE(b.newton.iterations, 1) << "step " << k;
    }
  }
  EXPECT_LE((plain.x() - carried.x()).lpNorm<Eigen::Infinity>(), 1e-8) << "the same answers";
}

TEST(Simulation, RefusesACoordinateHeldByTwoSetsAndBadSizes) {
  SimulationSetup s = pulled_box(Integrator::quasi_static);
  s.kinematic.push_back(s.kinematic[0]);
  s.kinematic.back().name = "again";
  s.kinematic.back().axes = {false, true, false};
  try {
    Simulation sim(s);
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "again holds the y coordinate of vertex 0, which bottom already holds: give each coordinate "
                                     "one motion");
  }
  s = pulled_box(Integrator::quasi_static);
  s.kinematic[1].vertices.push_back(999);
  EXPECT_THROW(Simulation{s}, std::invalid_argument);
  s = pulled_box(Integrator::quasi_static);
  s.initial = Eigen::VectorXd::Zero(5);
  EXPECT_THROW(Simulation{s}, std::invalid_argument);
  s = pulled_box(Integrator::backward_euler);
  s.dt = 0.0;
  EXPECT_THROW(Simulation{s}, std::invalid_argument);
}

TEST(ScriptedMotion, ComposesItsMotionsInOrder) {
  const Eigen::Matrix3Xd base = (Eigen::Matrix3Xd(3, 2) << 1, 3, 0, 0, 0, 0).finished();
  const ScriptedMotion m(base, {Rotate{.axis = Eigen::Vector3d::UnitZ(), .radians = std::numbers::pi / 2, .center = {}, .start = 0, .end = 1},
                                Translate{.by = Eigen::Vector3d(0, 0, 4), .start = 1, .end = 3},
                                Scale{.factors = Eigen::Vector3d(3, 1, 1), .center = Eigen::Vector3d::Zero(), .start = 3, .end = 4}});
  Eigen::Matrix3Xd P;
  m.targets(0.0, P);
  EXPECT_EQ(P, base);
  m.targets(1.0, P);  // turned 90° about the centroid (2, 0, 0)
  EXPECT_TRUE(P.isApprox((Eigen::Matrix3Xd(3, 2) << 2, 2, -1, 1, 0, 0).finished(), 1e-15));
  m.targets(2.0, P);  // half way up
  EXPECT_TRUE(P.row(2).isApprox(Eigen::RowVector2d(2, 2)));
  m.targets(10.0, P);  // all of it, x scaled ×3 about the origin
  EXPECT_TRUE(P.isApprox((Eigen::Matrix3Xd(3, 2) << 6, 6, -1, 1, 4, 4).finished(), 1e-15));
}

TEST(StatsTables, OneDescriptionDrivesJsonCsvAndResume) {
  StepRecord r;
  r.index = 3;
  r.time = 0.75;
  r.converged = false;
  r.newton_iterations = 7;
  r.residual = 1.5e-4;
  r.energy = 2.25;
  r.elastic_energy = std::numeric_limits<double>::infinity();
  r.min_J = -0.5;
  r.inverted = 2;
  r.residuals = {1.0, 0.1, 1.5e-4};
  r.failure = "no convergence";
  for (const RecordTable* t : {&stretch_table(), &scene_table()}) {
    const json j = to_json(*t, r);
    const StepRecord back = from_json(*t, j);
    EXPECT_EQ(to_json(*t, back), j) << t->records;
    EXPECT_EQ(j.at(t->index), 3);
    EXPECT_EQ(back.failure, "no convergence");
    // Every CSV column is a field of the record, in the table's order.
    std::string expected;
    for (const RecordField& f : t->fields)
      if (f.csv) expected += (expected.empty() ? "" : ",") + std::string(f.key);
    EXPECT_EQ(csv_header(*t), expected);
    const std::string row = csv_row(*t, r);
    EXPECT_EQ(std::count(row.begin(), row.end(), ','), std::count(expected.begin(), expected.end(), ','));
    // Every plot named by a field exists, and every plot has a field.
    const json schema = schema_json(*t);
    for (const json& p : schema["plots"]) {
      int series = 0;
      for (const json& c : schema["columns"]) series += c.value("plot", "") == p["id"];
      EXPECT_GT(series, 0) << p["id"];
    }
    EXPECT_EQ(table_for(t->records), t);
  }
  EXPECT_TRUE(to_json(scene_table(), r)["elastic_energy"].is_null()) << "non-finite numbers are written as null";
  EXPECT_TRUE(std::isnan(from_json(scene_table(), to_json(scene_table(), r)).elastic_energy));
  // The columns these files have (the scenes' assembly and solve times added after wall_seconds, issue 15; the
  // last complete Newton step after the residual, issue 31).
  EXPECT_EQ(csv_header(stretch_table()), "step,converged,newton_iterations,line_search_steps,linear_iterations,factorizations,"
                                         "residual,energy,wall_seconds,assembly_seconds,solve_seconds,min_J,inverted,volume_ratio");
  EXPECT_EQ(csv_header(scene_table()), "frame,time,substeps,converged,newton_iterations,line_search_steps,linear_iterations,"
                                       "factorizations,residual,newton_step,elastic_energy,kinetic_energy,gravity_energy,total_energy,"
                                       "volume_ratio,min_J,inverted,wall_seconds,assembly_seconds,solve_seconds");
  EXPECT_EQ(csv_row(stretch_table(), r), "3,0,7,0,0,0,1.500000e-04,2.25,0.000000,0.000000,0.000000,-0.5,2,1");
  // A value that does not exist (the NaN energy here; min_contact_distance with no pair in range) is an empty
  // CSV field, as JSON writes null: no nan reaches the file.
  const std::string row = csv_row(scene_table(), r);
  EXPECT_EQ(row.find("nan"), std::string::npos) << row;
  EXPECT_NE(row.find(",,"), std::string::npos) << row;
}

json stats_of(const fs::path& dir) {
  std::ifstream in(dir / "stats.json");
  return json::parse(in);
}

TEST(Driver, WritesTheRunsStatus) {
  const fs::path d = fs::temp_directory_path() / ("snh_test_driver_" + std::to_string(::getpid()));
  fs::remove_all(d);
  std::ostringstream log;
  StretchConfig c;
  c.resolution = 2;
  c.steps = 3;
  c.out = d / "ok";
  ASSERT_TRUE(run_stretch(c, log).all_converged);
  json s = stats_of(c.out);
  EXPECT_EQ(s["status"], "finished");
  EXPECT_EQ(s["all_converged"], true);
  EXPECT_EQ(s["schema"]["records"], "steps");
  // A step that fails: "stopped".
  c.out = d / "failed";
  c.newton.max_iterations = 1;
  c.newton.tolerance = 1e-14;
  const StretchResult failed = run_stretch(c, log);
  EXPECT_FALSE(failed.all_converged);
  s = stats_of(c.out);
  EXPECT_EQ(s["status"], "stopped");
  EXPECT_EQ(s["all_converged"], false);
  EXPECT_EQ(s["failure"].get<std::string>().rfind("step 1, no convergence in 1 Newton iterations", 0), 0u) << s["failure"];
  // A signal: "interrupted".
  c.out = d / "stopped";
  c.newton = {};
  c.newton.on_iteration = [](int it, double) {
    if (it == 1) request_stop(SIGTERM);
  };
  const StretchResult stopped = run_stretch(c, log);
  request_stop(0);
  EXPECT_EQ(stopped.interrupted_by, SIGTERM);
  s = stats_of(c.out);
  EXPECT_EQ(s["status"], "interrupted");
  EXPECT_EQ(s["interrupted_by_signal"], SIGTERM);
  fs::remove_all(d);
}

TEST(SceneSections, MixedOrMeaninglessInputIsRefused) {
  auto error_of = [](const char* text) {
    try {
      (void)build_scene(parse_scene(json::parse(text), "s.json"));
    } catch (const SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  // A centre means nothing to a translation.
  EXPECT_EQ(error_of(R"({"pins": [{"indices": [0], "motion": [{"type": "translate", "by": [1, 0, 0], "center": [0, 0, 0]}]}]})")
                .rfind("s.json: pins[0].motion[0].center: unknown key", 0),
            0u);
  // Two pin sets moving the same coordinate of a vertex.
  EXPECT_EQ(error_of(R"({"pins": [{"indices": [0, 1]}, {"indices": [1], "axes": "y",
                       "motion": [{"type": "translate", "by": [0, 1, 0]}]}]})"),
            "s.json: pins[1] holds the y coordinate of vertex 1, which pins[0] already holds: give each coordinate one "
            "motion");
  // The same vertex held on different axes by two sets is fine.
  EXPECT_EQ(error_of(R"({"pins": [{"indices": [0, 1], "axes": "x"}, {"indices": [1], "axes": "yz"}]})"), "");
}

/// docs/library.md's example, as written there.
class Lift final : public snh::KinematicProvider {  // where the set's vertices are at time t
 public:
  explicit Lift(Eigen::Matrix3Xd rest) : rest_(std::move(rest)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    out = rest_;
    out.row(1).array() += 0.1 * t;
  }

 private:
  Eigen::Matrix3Xd rest_;
};

TEST(LibraryUse, SteppingASimulation) {
  snh::SimulationSetup setup;
  setup.mesh = snh::box_hexes(8);
  setup.materials = {snh::make_material("stable_neo_hookean", {1.0, 10.0})};
  setup.integrator = snh::Integrator::backward_euler;
  setup.dt = 0.01;
  snh::KinematicSet top;
  top.name = "top";
  for (Eigen::Index v = 0; v < setup.mesh.vertex_count(); ++v)
    if (setup.mesh.vertices(1, v) == 1.0) top.vertices.push_back(static_cast<int>(v));
  top.provider = std::make_shared<Lift>(setup.mesh.vertices(Eigen::all, top.vertices));
  setup.kinematic = {top};
  snh::Simulation sim(std::move(setup));
  for (int k = 1; k <= 20; ++k) {
    const snh::StepReport r = sim.step(0.01 * k);  // one backward Euler step to time t
    if (!r.converged) throw std::runtime_error(r.failure);
  }
  const Eigen::VectorXd& x = sim.x();  // 3 #V positions
  // The top layer rose by 0.1 t = 0.02; the rest of the free body followed part of the way.
  EXPECT_NEAR(x[3 * sim.setup().kinematic[0].vertices[0] + 1], 1.02, 1e-12);
  EXPECT_GT(x.maxCoeff(), 1.0);
}

}  // namespace
}  // namespace snh
