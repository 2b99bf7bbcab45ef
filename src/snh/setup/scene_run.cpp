#include "snh/setup/scene_run.hpp"

#include <algorithm>
#include <limits>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/run/driver.hpp"
#include "snh/setup/contact_setup.hpp"
#include "snh/setup/flesh_scene.hpp"
#include "snh/setup/scene_build.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

const char* cells_name(const VolumeMesh& mesh) { return mesh.type == CellType::tet4 ? "tets" : "hexes"; }

/// Newton's stopping rule in words, for the header line.
std::string stopping_rule(const NewtonOptions& o) {
  std::string rule;
  if (o.tolerance > 0.0) rule = fmt::format("|g| < {:.3g}", o.tolerance);
  if (o.step_tolerance > 0.0) rule += fmt::format("{}a step < {:.3g}", rule.empty() ? "" : " or ", o.step_tolerance);
  if (o.relative_step_tolerance > 0.0)
    rule += fmt::format("{}a step < {:.3g} of its motion", rule.empty() ? "" : " or ", o.relative_step_tolerance);
  return fmt::format("Newton stops at {}, or fails after {} iterations", rule, o.max_iterations);
}

/// stats.json's description of the run: the scene's sections as built (every default resolved), what the
/// solver "auto" chose, and the body's size.
json scene_settings(const BuiltScene& b, const Simulation& sim) {
  const Scene& s = b.scene;
  const VolumeMesh& mesh = b.body->mesh;
  json j;
  j["program"] = s.run.program;
  if (!s.run.command_line.empty()) j["command_line"] = s.run.command_line;
  j["scene"] = s.source.string();
  j["element"] = std::string(to_string(mesh.type));
  if (s.mesh.file.empty()) j["resolution"] = s.mesh.resolution;
  else j["mesh_file"] = s.mesh.file.string();
  j["material"] = s.material.name;
  j["mu"] = s.material.params.mu;
  j["lambda"] = s.material.params.lambda;
  j["reparametrize"] = s.material.reparametrize;
  j["density"] = s.material.density;
  j["integrator"] = integrator_name(s.time.integrator);
  j["dt"] = s.time.dt;
  j["end_time"] = b.end_time;
  j["gravity"] = {s.forces.gravity[0], s.forces.gravity[1], s.forces.gravity[2]};
  j["mass_damping"] = s.forces.mass_damping;
  j["stiffness_damping"] = s.forces.stiffness_damping;
  j["solver"] = std::string(sim.solver().name());  // what "auto" chose
  j["tolerance"] = b.newton.tolerance;
  j["step_tolerance"] = b.newton.step_tolerance;
  j["relative_step_tolerance"] = b.newton.relative_step_tolerance;
  j["max_newton_iterations"] = b.newton.max_iterations;
  j["vertices"] = mesh.vertex_count();
  j["cells"] = mesh.cell_count();
  if (s.contact.enabled) {
    const ContactSpec& c = s.contact;
    json planes = json::array();
    for (const PlaneColliderSpec& p : c.planes)
      planes.push_back({{"point", {p.point[0], p.point[1], p.point[2]}}, {"normal", {p.normal[0], p.normal[1], p.normal[2]}}});
    j["contact"] = {{"self", c.self},
                    {"dhat", b.contact.dhat},
                    {"stiffness", b.contact.stiffness},
                    {"stiffness_auto", !c.stiffness && !b.body->flesh},  // IPC's automatic κ (a flesh's default is its own)
                    {"planes", planes},
                    {"colliders", c.planes.size() + c.colliders.size()},
                    {"friction", c.friction}};
    if (c.friction > 0.0) j["contact"]["friction_velocity"] = b.contact.slip_velocity;
  }
  return j;
}

/// The header: the mesh file, the body and material, the time stepping, the solver and where it writes.
void write_header(const BuiltScene& b, const Simulation& sim, std::ostream& o) {
  const Scene& s = b.scene;
  const VolumeMesh& mesh = b.body->mesh;
  const bool dynamic = is_dynamic(s.time.integrator);
  if (!s.mesh.file.empty())
    o << fmt::format("mesh {}: {} vertices, {} {}{}\n", s.mesh.file.string(), mesh.vertex_count(), mesh.cell_count(), cells_name(mesh),
                     b.body->reoriented ? fmt::format("; warning: {} inverted cell(s) re-oriented", b.body->reoriented) : "");
  o << fmt::format("{} {}: {} {} ({} vertices), material {}, mu {:g}, lambda {:g}{}, density {:g}\n", s.run.program,
                   s.source.string(), mesh.cell_count(), cells_name(mesh), mesh.vertex_count(), s.material.name, s.material.params.mu,
                   s.material.params.lambda, s.material.reparametrize ? " (linear, reparametrized)" : "", s.material.density);
  o << fmt::format("{}, {} frames to t = {:g}{}, gravity ({:g}, {:g}, {:g}), solver {} ({}), output {}\n",
                   s.time.integrator == Integrator::bdf2 ? "BDF2" : s.time.integrator == Integrator::tr_bdf2 ? "TR-BDF2" : dynamic ? "backward Euler" : "quasi-static", b.frames, b.end_time,
                   dynamic ? fmt::format(" ({} substeps of {:g} per frame)", b.substeps, b.substep) : "", s.forces.gravity[0],
                   s.forces.gravity[1], s.forces.gravity[2],
                   s.solver.linear == "auto" ? fmt::format("{} (auto)", sim.solver().name()) : s.solver.linear,
                   stopping_rule(sim.setup().newton), s.output.dir.string());
  if (s.contact.enabled)
    o << fmt::format("contact: dhat {:.4g}, stiffness {:.4g} ({}){}{}{}\n", b.contact.dhat, b.contact.stiffness, b.contact_stiffness_rule,
                     s.contact.self ? ", self-contact" : "", s.contact.planes.size() + s.contact.colliders.size() == 0 ? "" : fmt::format(", {} colliders", s.contact.planes.size() + s.contact.colliders.size()),
                     s.contact.friction > 0.0 ? fmt::format(", friction {:g}", s.contact.friction) : "");
  if (b.muscles)
    for (const std::string& line : b.muscles->summary) o << line << "\n";
}

/// The contact terms' statistics in every frame's record (contact_table): active pairs and the smallest
/// distance at the frame's solution, and what the terms counted during its solve (Term::report_contact, which
/// then starts their counts anew); the progress line gets the pairs and the distance.
void add_contact_statistics(Simulation& sim, RunPlan& plan) {
  plan.table = &contact_table(*plan.table);
  const auto base_fill = plan.fill;
  plan.fill = [&sim, base_fill](StepRecord& r, const StepReport* rep) {
    if (base_fill) base_fill(r, rep);
    ContactStatistics c;
    for (Term* t : sim.problem().terms()) t->report_contact(sim.x(), c);
    r.contact_pairs = c.pairs;
    r.min_contact_distance = c.min_distance;
    r.ccd_calls = static_cast<int>(std::min<long long>(c.ccd_calls, std::numeric_limits<int>::max()));
    r.ccd_tests = static_cast<int>(std::min<long long>(c.ccd_tests, std::numeric_limits<int>::max()));
    r.contact_seconds = c.seconds;
  };
  const auto base_line = plan.line;
  // (A shape's or plane's distance is signed: below 0 only at a frame that failed, a point behind or inside it.)
  plan.line = [base_line](const StepRecord& r) {
    if (r.contact_pairs == 0) return base_line(r) + ", no contact pairs";
    if (r.min_contact_distance < 0.0)
      return base_line(r) + fmt::format(", {} contact pairs, a point {:.3g} inside a collider", r.contact_pairs, -r.min_contact_distance);
    return base_line(r) + fmt::format(", {} contact pairs, min distance {:.3g}", r.contact_pairs, r.min_contact_distance);
  };
}

/// The driver's plan for a scene: its frames and substeps, the fingerprint a resume must match, and the log's
/// header and lines; a flesh's output and contact statistics added where the scene has them.
/// A frame's inverted elements, said on its progress line; a converged frame holding any is warned of (its
/// equilibrium has flesh turned inside out: a bone through the skin, a joint bent past what the cells allow).
std::string inverted_note(const StepRecord& f) {
  if (f.inverted == 0) return "";
  return fmt::format(", {} inverted element{}{}", f.inverted, f.inverted == 1 ? "" : "s",
                     f.converged ? " (warning: converged with flesh turned inside out)" : "");
}

/// A scene with muscles: each frame's line gives their activation; muscles.json (muscles_json, every frame's
/// time) is written with the initial state, and stats.json names it.
void add_muscle_output(const BuiltScene& b, RunPlan& plan) {
  const std::shared_ptr<const BuiltMuscles> m = b.muscles;
  if (!m->muscles.empty()) {
    const auto base_line = plan.line;
    plan.line = [m, base_line](const StepRecord& r) {
      std::string s = base_line(r);
      const std::vector<double> a = m->activation(r.time);
      for (std::size_t i = 0; i < a.size(); ++i) s += fmt::format("{} {} {:.3f}", i ? "," : ", activation", m->muscles[i].name, a[i]);
      return s;
    };
  }
  // Written with the initial state (activation depends on the time alone: every frame's is known), so that a
  // run killed on the way keeps it; a resumed run finds it there.
  std::vector<double> times;
  for (int i = 0; i <= plan.frames; ++i) times.push_back(i * plan.frame_duration);
  const auto base_fill = plan.fill;
  plan.fill = [&b, m, times, out = plan.out, base_fill](StepRecord& r, const StepReport* rep) {
    if (base_fill) base_fill(r, rep);
    if (rep) return;
    const nlohmann::json j = muscles_json(*m, b.scene, b.body->mesh, times);
    write_atomically(out / "muscles.json", [&](std::ostream& o) { o << j.dump() << '\n'; });
  };
  const auto base_finish = plan.finish;
  plan.finish = [base_finish](const RunResult& result, nlohmann::json& stats) {
    if (base_finish) base_finish(result, stats);
    stats["muscles_file"] = "muscles.json";
  };
}

RunPlan scene_plan(const BuiltScene& b, Simulation& sim) {
  const Scene& s = b.scene;
  RunPlan plan;
  plan.out = s.output.dir;
  plan.lock = s.run.lock;
  plan.table = &scene_table();
  plan.frames = b.frames;
  plan.frame_duration = b.end_time / b.frames;
  plan.substeps = b.substeps;
  plan.substep = b.substep;
  plan.write_vtu = s.output.vtu;
  plan.resume = s.run.resume;
  plan.keep_going = s.run.keep_going;
  // The scene as parsed (or its source, for one built in code) and the mesh file's (model's) contents.
  plan.fingerprint = "scene " + (s.settings.empty() ? s.source.string() : s.settings) +
                     (b.body->digest.empty() ? "" : " mesh contents " + b.body->digest);
  plan.settings = scene_settings(b, sim);
  if (b.body->reoriented)  // the header's mesh line says so
    plan.warnings.push_back(fmt::format("{} inverted cell(s) of the mesh re-oriented", b.body->reoriented));
  plan.live_progress = s.run.live_progress;
  plan.header = [&b, &sim](std::ostream& o) { write_header(b, sim, o); };
  plan.fill = [&sim](StepRecord& f, const StepReport*) {
    const Eigen::VectorXd& x = sim.x();
    f.elastic_energy = sim.elastic().energy(x);
    f.kinetic_energy = sim.inertia().kinetic_energy(sim.v());
    f.gravity_energy = sim.inertia().gravity_energy(x);
    f.total_energy = f.elastic_energy + f.kinetic_energy + f.gravity_energy;
  };
  // Shape colliders' faces: a frame whose shape met the surface between its points is no result.
  const bool shapes = s.contact.enabled && std::any_of(s.contact.colliders.begin(), s.contact.colliders.end(), is_shape_collider);
  if (shapes) {
    auto surface = std::make_shared<const ContactSurface>(contact_surface_of(*b.body));
    auto previous = std::make_shared<Eigen::VectorXd>();  // the last frame's state (empty after a resume)
    const double frame_duration = plan.frame_duration;
    plan.fill = [&sim, &s, surface, previous, frame_duration, base = plan.fill](StepRecord& f, const StepReport* rep) {
      base(f, rep);
      const Eigen::VectorXd& x = sim.x();
      if (rep && f.converged) {
        const bool known = previous->size() == x.size();
        const std::string crossing = shape_collider_crossing(s.contact, *surface, known ? *previous : x, x,
                                                             known ? f.time - frame_duration : f.time, f.time);
        if (!crossing.empty()) f.converged = false, f.failure = crossing;
      }
      *previous = x;
    };
  }
  const int frames = b.frames, substeps = b.substeps;
  plan.line = [frames](const StepRecord& f) {
    if (f.index == 0)
      return fmt::format("frame {:>3}/{}: t = {:.4g}, volume {:.4f}, min J {:.4f}{}", 0, frames, 0.0, f.volume_ratio, f.min_J,
                         f.failure.empty() ? "" : "  " + f.failure);
    return fmt::format("frame {:>3}/{}: t = {:.4g}, {} Newton iterations{}, |g| = {:.2e}, energy {:.8g} (kinetic {:.4g}), "
                       "volume {:.4f}, min J {:.4f}, {:.3f} s{}{}",
                       f.index, frames, f.time, f.newton_iterations,
                       f.halvings == 0 ? "" : fmt::format(" ({} substeps: a step retried in halves)", f.substeps), f.residual,
                       f.total_energy, f.kinetic_energy, f.volume_ratio, f.min_J, f.wall_seconds, inverted_note(f),
                       f.converged ? "" : "  NOT CONVERGED: " + f.failure);
  };
  plan.live = [frames, substeps](int frame, int sub, int it, double r) {
    return fmt::format("frame {:>3}/{}: substep {}/{}, Newton iteration {}, |g| = {:.2e} ...", frame, frames, sub, substeps, it, r);
  };
  plan.failure = [](const StepReport& r) {
    return fmt::format("substep {} (t = {:.6g}): {}", r.failed_substep, r.failed_time, r.failure);
  };
  plan.summary = [out = s.output.dir, frames](const RunResult& r) {
    std::string how = r.all_converged ? "finished" : "STOPPED: " + r.failure;
    if (!r.failed_frame.empty()) how += "; its last iterate: " + r.failed_frame;
    // Converged frames that hold inverted elements are warned of on their lines; the last line counts them,
    // so that a run that "finished" is not read as clean.
    if (const InsideOut io = inside_out_frames(r.records); r.all_converged && io.frames > 0)
      how = fmt::format("finished, {} frame{} with inverted elements (warning: flesh turned inside out; at most {}, in frame {})",
                        io.frames, io.frames == 1 ? "" : "s", io.most, io.worst);
    if (!r.unconverged.empty() && r.interrupted_by == 0 && !r.records.empty() && r.records.back().index == frames) {
      std::string list;
      for (std::size_t i = 0; i < r.unconverged.size() && i < 10; ++i) list += fmt::format("{}{}", i ? ", " : "", r.unconverged[i]);
      if (r.unconverged.size() > 10) list += ", …";
      how = fmt::format("FINISHED WITH {} FRAME{} NOT CONVERGED ({}; kept going past them: their results cannot be trusted): first {}",
                        r.unconverged.size(), r.unconverged.size() == 1 ? "" : "S", list, r.failure);
    }
    return fmt::format("{} in {:.3f} s (peak memory {:.0f} MiB); frames, stats.json and stats.csv in {}", how, r.total_seconds,
                       r.peak_memory_mib, out.string());
  };
  if (b.body->flesh) add_flesh_output(b, sim, plan);
  if (b.muscles) add_muscle_output(b, plan);
  if (sim.has_contact()) add_contact_statistics(sim, plan);
  return plan;
}

}  // namespace

SceneResult run_scene(const BuiltScene& b, std::ostream& log) {
  const Scene& s = b.scene;
  if (s.output.dir.empty()) throw SceneError(fmt::format("{}: no output directory", s.source.string()));
  const VolumeMesh& mesh = b.body->mesh;
  Simulation sim(simulation_setup(b));
  const RunPlan plan = scene_plan(b, sim);
  SceneResult result;
  result.element = mesh.type;
  result.vertices = mesh.vertex_count();
  result.cells = mesh.cell_count();
  if (s.run.check_only) {
    plan.header(log);
    log << fmt::format("checked: {} {}, {} vertices, {} free DOFs; no frame run\n", mesh.cell_count(), cells_name(mesh),
                       mesh.vertex_count(), sim.problem().dofs().free_count());
    return result;
  }
  RunResult run = run_simulation(sim, plan, log);
  static_cast<RunOutcome&>(result) = run;
  result.frames = std::move(run.records);
  result.final_positions = sim.x();
  return result;
}

SceneResult run_scene(const Scene& scene, std::ostream& log) { return run_scene(build_scene(scene), log); }

}  // namespace snh
