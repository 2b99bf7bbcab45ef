#include "snh/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/checksum.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/material/registry.hpp"
#include "snh/sim/driver.hpp"
#include "snh/sim/scene/sections.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

Eigen::Vector3d centre_of(const Eigen::Matrix3Xd& X) { return 0.5 * (X.rowwise().minCoeff() + X.rowwise().maxCoeff()); }

}  // namespace

Scene parse_scene(const json& j, const std::filesystem::path& source) {
  Scene s;
  s.source = source;
  scene::Keys top(j, "", source.string());
  s.mesh = scene::parse_mesh(top, source);
  s.material = scene::parse_material(top);
  s.time = scene::parse_time(top);
  s.forces = scene::parse_forces(top);
  s.pins = scene::parse_pins(top, s.time.end_time);
  s.initial = scene::parse_initial(top);
  s.solver = scene::parse_solver(top);
  s.output = scene::parse_output(top, source);
  top.finish();
  s.settings = j.dump();  // object keys sorted: the same text for the same scene

  // The mesh, read once; the pins must select something on it and hold each coordinate once.
  s.loaded = scene_mesh(s);
  const Eigen::VectorXd x0 = initial_positions(s, s.loaded->mesh);
  try {
    (void)kinematic_dof_flags(scene_kinematics(s, s.loaded->mesh, x0), s.loaded->mesh.vertex_count());
  } catch (const SceneError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
  return s;
}

Scene load_scene(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw SceneError(fmt::format("{}: cannot open the scene file", file.string()));
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    // nlohmann's message names the byte; keep it on one line.
    throw SceneError(fmt::format("{}: not valid JSON: {}", file.string(), e.what()));
  }
  return parse_scene(j, file);
}

std::shared_ptr<const SceneMesh> scene_mesh(const Scene& s) {
  if (s.loaded) return s.loaded;
  auto out = std::make_shared<SceneMesh>();
  const MeshSpec& m = s.mesh;
  if (!m.file.empty()) {
    MeshFile f = read_mesh(m.file);
    out->mesh = std::move(f.mesh);
    out->reoriented = f.reoriented;
    out->digest = file_digest(m.file);
    return out;
  }
  out->mesh = m.element == CellType::tet4 ? box_tets(m.resolution, m.tet_split) : box_hexes(m.resolution);
  // [−1, 1]³ → [min, max]
  const Eigen::Vector3d half = 0.5 * (m.max - m.min), mid = 0.5 * (m.max + m.min);
  out->mesh.vertices = (half.asDiagonal() * out->mesh.vertices).colwise() + mid;
  return out;
}

std::vector<int> select_vertices(const Selection& s, const Eigen::Matrix3Xd& X, const std::string& where) {
  std::vector<int> out;
  if (s.region) {
    const Eigen::Vector3d lo = X.rowwise().minCoeff(), hi = X.rowwise().maxCoeff();
    const double eps = 1e-9 * std::max((hi - lo).norm(), 1e-300);
    for (Eigen::Index v = 0; v < X.cols(); ++v)
      if ((X.col(v).array() >= s.region->min().array() - eps).all() && (X.col(v).array() <= s.region->max().array() + eps).all())
        out.push_back(static_cast<int>(v));
    if (out.empty()) throw SceneError(fmt::format("{}: the region selects no vertex", where));
  } else {
    for (int i : s.indices) {
      if (i >= X.cols()) throw SceneError(fmt::format("{}: vertex index {} is out of range (the mesh has {} vertices)", where, i, X.cols()));
      out.push_back(i);
    }
  }
  return out;
}

Eigen::VectorXd initial_positions(const Scene& s, const VolumeMesh& mesh) {
  Eigen::Matrix3Xd X = mesh.vertices;
  for (std::size_t i = 0; i < s.initial.size(); ++i)
    std::visit(
        [&](const auto& op) {
          using Op = std::decay_t<decltype(op)>;
          if constexpr (std::is_same_v<Op, ScaleOp>) {
            const Eigen::Vector3d c = op.center.value_or(centre_of(X));
            X = (op.factors.asDiagonal() * (X.colwise() - c)).colwise() + c;
          } else if constexpr (std::is_same_v<Op, ReflectOp>) {
            const Eigen::Vector3d c = op.center.value_or(centre_of(X));
            X.row(op.axis) = (2.0 * c[op.axis] - X.row(op.axis).array()).matrix();
          } else if constexpr (std::is_same_v<Op, CollapseOp>) {
            const Eigen::Vector3d c = op.center.value_or(centre_of(X));
            for (int a = 0; a < 3; ++a) {
              const bool flatten = op.to == CollapseOp::To::point || (op.to == CollapseOp::To::plane && a == op.axis) ||
                                   (op.to == CollapseOp::To::line && a != op.axis);
              if (flatten) X.row(a).setConstant(c[a]);
            }
          } else if constexpr (std::is_same_v<Op, PerturbOp>) {
            std::mt19937_64 rng(op.seed);
            std::uniform_real_distribution<double> u(-op.amplitude, op.amplitude);
            for (Eigen::Index v = 0; v < X.cols(); ++v)
              for (int a = 0; a < 3; ++a) X(a, v) += u(rng);
          } else {
            for (int v : select_vertices(op.select, X, fmt::format("{}: initial[{}]", s.source.string(), i))) X.col(v) += op.by;
          }
        },
        s.initial[i]);
  return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
}

std::vector<KinematicSet> scene_kinematics(const Scene& s, const VolumeMesh& mesh, const Eigen::VectorXd& x0) {
  std::vector<KinematicSet> sets;
  const Eigen::Map<const Eigen::Matrix3Xd> X0(x0.data(), 3, mesh.vertex_count());
  for (std::size_t i = 0; i < s.pins.size(); ++i) {
    const std::string name = fmt::format("{}: pins[{}]", s.source.string(), i);
    KinematicSet set;
    set.name = name;
    set.vertices = select_vertices(s.pins[i].select, mesh.vertices, name);
    set.axes = s.pins[i].axes;
    set.provider = std::make_shared<ScriptedMotion>(X0(Eigen::all, set.vertices), s.pins[i].motions);
    sets.push_back(std::move(set));
  }
  return sets;
}

SceneResult run_scene(const Scene& s, std::ostream& log) {
  if (s.output.dir.empty()) throw SceneError(fmt::format("{}: no output directory", s.source.string()));
  const std::shared_ptr<const SceneMesh> loaded = scene_mesh(s);
  const VolumeMesh& mesh = loaded->mesh;
  const Eigen::VectorXd x0 = initial_positions(s, mesh);
  const bool dynamic = s.time.integrator == Integrator::backward_euler;
  const double frame_dt = s.time.end_time / s.time.frames;
  const int substeps = dynamic ? std::max(1, static_cast<int>(std::ceil(frame_dt / s.time.dt - 1e-9))) : 1;
  const double h = frame_dt / substeps;

  SimulationSetup setup;
  setup.mesh = mesh;
  setup.materials = {make_material(s.material.name, s.material.params, s.material.reparametrize)};
  setup.density = s.material.density;
  setup.integrator = s.time.integrator;
  setup.dt = h;
  setup.gravity = s.forces.gravity;
  setup.mass_damping = s.forces.mass_damping;
  setup.stiffness_damping = s.forces.stiffness_damping;
  setup.kinematic = scene_kinematics(s, mesh, x0);
  setup.initial = x0;
  setup.linear.name = s.solver.linear;
  setup.linear.reuse_factor = !s.solver.refactorize;
  setup.newton = s.solver.newton;
  Simulation sim(std::move(setup));

  SceneResult result;
  result.element = mesh.type;
  result.vertices = mesh.vertex_count();
  result.cells = mesh.cell_count();
  const char* cells = mesh.type == CellType::tet4 ? "tets" : "hexes";

  json settings;
  settings["program"] = "snh run";
  if (!s.run.command_line.empty()) settings["command_line"] = s.run.command_line;
  settings["scene"] = s.source.string();
  settings["element"] = std::string(to_string(mesh.type));
  if (s.mesh.file.empty()) settings["resolution"] = s.mesh.resolution;
  else settings["mesh_file"] = s.mesh.file.string();
  settings["material"] = s.material.name;
  settings["mu"] = s.material.params.mu;
  settings["lambda"] = s.material.params.lambda;
  settings["reparametrize"] = s.material.reparametrize;
  settings["density"] = s.material.density;
  settings["integrator"] = dynamic ? "backward_euler" : "quasi_static";
  settings["dt"] = s.time.dt;
  settings["end_time"] = s.time.end_time;
  settings["gravity"] = {s.forces.gravity[0], s.forces.gravity[1], s.forces.gravity[2]};
  settings["mass_damping"] = s.forces.mass_damping;
  settings["stiffness_damping"] = s.forces.stiffness_damping;
  settings["solver"] = s.solver.linear;
  settings["tolerance"] = s.solver.newton.tolerance;
  settings["vertices"] = result.vertices;
  settings["cells"] = result.cells;

  RunPlan plan;
  plan.out = s.output.dir;
  plan.lock = s.run.lock;
  plan.table = &scene_table();
  plan.frames = s.time.frames;
  plan.frame_duration = frame_dt;
  plan.substeps = substeps;
  plan.substep = h;
  plan.write_vtu = s.output.vtu;
  plan.resume = s.run.resume;
  // The scene as parsed (or its source, for one built in code) and the mesh file's contents.
  plan.fingerprint = "scene " + (s.settings.empty() ? s.source.string() : s.settings) +
                     (loaded->digest.empty() ? "" : " mesh contents " + loaded->digest);
  plan.settings = std::move(settings);
  plan.live_progress = s.run.live_progress;
  plan.header = [&](std::ostream& o) {
    if (!s.mesh.file.empty())
      o << fmt::format("mesh {}: {} vertices, {} {}{}\n", s.mesh.file.string(), mesh.vertex_count(), mesh.cell_count(), cells,
                       loaded->reoriented ? fmt::format("; warning: {} inverted cell(s) re-oriented", loaded->reoriented) : "");
    o << fmt::format("snh run {}: {} {} ({} vertices), material {}, mu {:g}, lambda {:g}{}, density {:g}\n", s.source.string(),
                     mesh.cell_count(), cells, mesh.vertex_count(), s.material.name, s.material.params.mu,
                     s.material.params.lambda, s.material.reparametrize ? " (linear, reparametrized)" : "", s.material.density);
    o << fmt::format("{}, {} frames to t = {:g}{}, gravity ({:g}, {:g}, {:g}), solver {}, output {}\n",
                     dynamic ? "backward Euler" : "quasi-static", s.time.frames, s.time.end_time,
                     dynamic ? fmt::format(" ({} substeps of {:g} per frame)", substeps, h) : "", s.forces.gravity[0],
                     s.forces.gravity[1], s.forces.gravity[2], s.solver.linear, s.output.dir.string());
  };
  plan.fill = [&](StepRecord& f, const StepReport*) {
    const Eigen::VectorXd& x = sim.x();
    f.elastic_energy = sim.elastic().energy(x);
    f.kinetic_energy = sim.inertia().kinetic_energy(sim.v());
    f.gravity_energy = sim.inertia().gravity_energy(x);
    f.total_energy = f.elastic_energy + f.kinetic_energy + f.gravity_energy;
  };
  plan.line = [&](const StepRecord& f) {
    if (f.index == 0)
      return fmt::format("frame {:>3}/{}: t = {:.4g}, volume {:.4f}, min J {:.4f}{}", 0, s.time.frames, 0.0, f.volume_ratio,
                         f.min_J, f.failure.empty() ? "" : "  " + f.failure);
    return fmt::format("frame {:>3}/{}: t = {:.4g}, {} Newton iterations, |g| = {:.2e}, energy {:.8g} (kinetic {:.4g}), "
                       "volume {:.4f}, min J {:.4f}, {:.3f} s{}",
                       f.index, s.time.frames, f.time, f.newton_iterations, f.residual, f.total_energy, f.kinetic_energy,
                       f.volume_ratio, f.min_J, f.wall_seconds, f.converged ? "" : "  NOT CONVERGED: " + f.failure);
  };
  plan.live = [&](int frame, int sub, int it, double r) {
    return fmt::format("frame {:>3}/{}: substep {}/{}, Newton iteration {}, |g| = {:.2e} ...", frame, s.time.frames, sub,
                       substeps, it, r);
  };
  plan.failure = [](const StepReport& r) {
    return fmt::format("substep {} (t = {:.6g}): {}", r.failed_substep, r.failed_time, r.failure);
  };
  plan.summary = [&](const RunResult& r) {
    return fmt::format("{} in {:.3f} s (peak memory {:.0f} MiB); frames, stats.json and stats.csv in {}",
                       r.all_converged ? "finished" : "STOPPED: " + r.failure, r.total_seconds, r.peak_memory_mib,
                       s.output.dir.string());
  };

  RunResult run = run_simulation(sim, plan, log);
  result.frames = std::move(run.records);
  result.all_converged = run.all_converged;
  result.failure = std::move(run.failure);
  result.interrupted_by = run.interrupted_by;
  result.total_seconds = run.total_seconds;
  result.peak_memory_mib = run.peak_memory_mib;
  result.final_positions = sim.x();
  return result;
}

}  // namespace snh
