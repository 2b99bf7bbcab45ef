#include "snh/setup/scene.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/io/checksum.hpp"
#include "snh/io/input_file.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/io/obj.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/io/usda.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/run/driver.hpp"
#include "snh/setup/contact_setup.hpp"
#include "snh/setup/scene/sections.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

Eigen::Vector3d centre_of(const Eigen::Matrix3Xd& X) { return 0.5 * (X.rowwise().minCoeff() + X.rowwise().maxCoeff()); }

/// f(), with a bad-input error from below (a rig, a kinematic set) turned into a SceneError of the same line.
template <class F>
auto as_scene_error(F&& f) {
  try {
    return f();
  } catch (const SceneError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
}

constexpr double max_substeps_in_run = 1e8;  ///< substeps a run may take in all (issue 13)
constexpr int max_frames = 100000;

/// Substeps per frame (backward Euler splits a frame into equal substeps no longer than dt; quasi-static: one),
/// computed in double so that no count overflows; a run that cannot be done (over 1e8 substeps in all, over
/// 100000 frames) is a SceneError naming the file and the value at fault.
int checked_substeps(const TimeSpec& t, const std::string& file) {
  if (t.frames < 1 || t.frames > max_frames)
    throw SceneError(fmt::format("{}: frames: must be from 1 to {}, got {}", file, max_frames, t.frames));
  if (!(t.end_time > 0.0) || !std::isfinite(t.end_time))
    throw SceneError(fmt::format("{}: end_time: must be a finite number > 0, got {:g}", file, t.end_time));
  if (t.integrator != Integrator::backward_euler) return 1;
  if (!(t.dt > 0.0) || !std::isfinite(t.dt)) throw SceneError(fmt::format("{}: dt: must be a finite number > 0, got {:g}", file, t.dt));
  const double per_frame = std::max(1.0, std::ceil(t.end_time / t.frames / t.dt - 1e-9));
  const double total = per_frame * t.frames;
  if (!(total <= max_substeps_in_run))
    throw SceneError(fmt::format("{}: dt: {:g} with end_time {:g} over {} frames makes {:.3g} substeps; at most {:g} can run "
                                 "(raise dt or lower end_time)",
                                 file, t.dt, t.end_time, t.frames, total, max_substeps_in_run));
  return static_cast<int>(per_frame);
}

/// Two pin sets may share a vertex, each holding its own coordinates; a moving set must then not move the
/// vertex along a coordinate that the other set holds elsewhere (a rotation about z, say, while another set holds
/// y still): the two would drive the vertex in different ways. Checked at the motions' starts, ends and
/// in between; `sets` are the scene's kinematic sets (its pins first).
void check_shared_pins(const Scene& s, const std::vector<KinematicSet>& sets) {
  const std::size_t pins = s.pins.size();
  if (pins < 2) return;
  std::vector<double> times{0.0, s.time.end_time};
  for (const PinSpec& p : s.pins)
    for (const Motion& m : p.motions)
      std::visit(
          [&](const auto& mo) {
            for (int k = 0; k <= 4; ++k) times.push_back(mo.start + 0.25 * k * (mo.end - mo.start));
          },
          m);
  std::map<int, std::vector<std::pair<std::size_t, Eigen::Index>>> at;  // vertex → (set, column)
  for (std::size_t i = 0; i < pins; ++i)
    for (std::size_t c = 0; c < sets[i].vertices.size(); ++c) at[sets[i].vertices[c]].push_back({i, static_cast<Eigen::Index>(c)});
  std::vector<Eigen::Matrix3Xd> targets(pins);
  for (double t : times) {
    for (std::size_t i = 0; i < pins; ++i) {
      targets[i].resize(3, static_cast<Eigen::Index>(sets[i].vertices.size()));
      sets[i].provider->targets(t, targets[i]);
    }
    for (const auto& [v, holders] : at)
      for (const auto& [moving, cm] : holders) {
        if (s.pins[moving].motions.empty()) continue;
        for (const auto& [other, co] : holders)
          for (int a = 0; a < 3; ++a) {
            if (other == moving || !sets[other].axes[a] || sets[moving].axes[a]) continue;
            const double x = targets[moving](a, cm), y = targets[other](a, co);
            if (std::abs(x - y) > 1e-9 * std::max({1.0, std::abs(x), std::abs(y)}))
              throw SceneError(fmt::format("{}: pins[{}] and pins[{}] both drive vertex {} in different ways: pins[{}] moves it along "
                                           "{} (to {:g} at t = {:g}), which pins[{}] holds at {:g}; give each vertex to one pin set",
                                           s.source.string(), std::min(moving, other), std::max(moving, other), v, moving,
                                           char('x' + a), x, t, other, y));
          }
      }
  }
}

/// Newton's stopping rule in words, for the header line.
std::string stopping_rule(const NewtonOptions& o) {
  std::string rule;
  if (o.tolerance > 0.0) rule = fmt::format("|g| < {:.3g}", o.tolerance);
  if (o.step_tolerance > 0.0) rule += fmt::format("{}a step < {:.3g}", rule.empty() ? "" : " or ", o.step_tolerance);
  if (o.relative_step_tolerance > 0.0)
    rule += fmt::format("{}a step < {:.3g} of its motion", rule.empty() ? "" : " or ", o.relative_step_tolerance);
  return "Newton stops at " + rule;
}

}  // namespace

NewtonOptions newton_options(const SolverSpec& solver, const VolumeMesh& rest, double youngs) {
  NewtonOptions o = solver.newton;
  if (o.tolerance == 0.0 && solver.force_fraction > 0.0 && rest.cell_count() > 0) {
    const double cell = std::cbrt(std::abs(mesh_volume(rest)) / static_cast<double>(rest.cell_count()));
    o.tolerance = solver.force_fraction * youngs * cell * cell;
  }
  return o;
}

Scene parse_scene(const json& j, const std::filesystem::path& source) {
  Scene s;
  s.source = source;
  scene::Keys top(j, "", source.string());
  s.flesh = scene::parse_flesh(top, source);
  s.mesh = scene::parse_mesh(top, source);
  s.material = scene::parse_material(top);
  s.time = scene::parse_time(top);
  if (s.flesh) {  // the paper's defaults for flesh: quasi-static, nu = 0.488, density of water
    if (!top.has("integrator")) s.time.integrator = Integrator::quasi_static;
    if (!top.has("material")) s.material.params = lame_from_youngs(FleshSpec::youngs, FleshSpec::poisson);
    if (!top.has("density")) s.material.density = FleshSpec::density;
  }
  s.forces = scene::parse_forces(top);
  s.pins = scene::parse_pins(top, s.time.end_time);
  s.initial = scene::parse_initial(top);
  s.solver = scene::parse_solver(top);
  s.contact = scene::parse_contact(top, s.time.integrator, source, s.time.end_time);
  s.output = scene::parse_output(top, source);
  top.finish();
  s.settings = j.dump();  // object keys sorted: the same text for the same scene

  // The mesh, read once (a flesh scene's: its volume and bones; the animation's length is the run's when
  // the scene gives none); the pins must select something on it and hold each coordinate once.
  if (!s.flesh) (void)checked_substeps(s.time, source.string());  // before the mesh is built (a flesh's clip may set end_time)
  s.loaded = as_scene_error([&] { return scene_mesh(s); });
  if (s.loaded->flesh) {
    // Newton's stopping rule at the flesh's own scale (unless the scene sets one): a force of 1e-6 of what a
    // unit strain puts on a cell's face (E h²), or a step under 1e-4 of a cell.
    const double h = s.loaded->flesh->cell_size, E = youngs_modulus(s.material.params);
    const json* solver = j.contains("solver") ? &j.at("solver") : nullptr;
    if (!solver || !solver->contains("tolerance")) s.solver.newton.tolerance = 1e-6 * E * h * h;
    if (!solver || !solver->contains("step_tolerance")) s.solver.newton.step_tolerance = 1e-4 * h;
    const double duration = s.loaded->flesh->clip.duration();
    if (!top.has("end_time") && duration > 0.0) s.time.end_time = duration;
    if (!top.has("frames")) {
      const double frames = std::max(1.0, std::round(s.time.end_time * FleshSpec::fps));
      if (!(frames <= max_frames))
        throw SceneError(fmt::format("{}: end_time: {:g} s at {:g} frames per second makes {:.3g} frames; at most {} can run",
                                     source.string(), s.time.end_time, FleshSpec::fps, frames, max_frames));
      s.time.frames = static_cast<int>(frames);
    }
  }
  if (s.flesh) (void)checked_substeps(s.time, source.string());
  if (s.loaded->flesh && s.contact.enabled) {  // contact's defaults at the flesh's scale
    if (s.contact.dhat == 0.0) s.contact.dhat = flesh_contact_dhat(*s.loaded->flesh);
    if (s.contact.stiffness == 0.0)
      s.contact.stiffness = flesh_contact_stiffness(*s.loaded->flesh, youngs_modulus(s.material.params), s.contact.dhat);
  }
  // Coordinates in range: a mesh file's (a box's are, from its checked corners), then after the initial operations.
  const Eigen::Matrix3Xd& X = s.loaded->mesh.vertices;
  for (Eigen::Index v = 0; v < X.cols(); ++v)
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(X(a, v)) <= scene::max_magnitude))
        throw SceneError(fmt::format("{}: {}: vertex {} has coordinate {:g}, beyond the {:g} a scene allows", source.string(),
                                     s.mesh.file.empty() ? std::string("mesh") : "mesh.file " + s.mesh.file.string(), v, X(a, v),
                                     scene::max_magnitude));
  const Eigen::VectorXd x0 = initial_positions(s, s.loaded->mesh);
  if (!(x0.array().abs() <= scene::max_magnitude).all())
    throw SceneError(fmt::format("{}: initial: the operations move a vertex beyond the {:g} a scene allows (largest coordinate {:g})",
                                 source.string(), scene::max_magnitude, x0.array().abs().maxCoeff()));
  (void)as_scene_error([&] { return kinematic_dof_flags(scene_kinematics(s, s.loaded->mesh, x0), s.loaded->mesh.vertex_count()); });
  check_shared_pins(s, scene_kinematics(s, s.loaded->mesh, x0));
  if (s.contact.enabled) {
    const ContactSurface surface = s.loaded->flesh ? skin_contact_surface(*s.loaded->flesh) : boundary_contact_surface(s.loaded->mesh);
    check_contact_start(s.contact, surface, s.loaded->mesh.vertices, x0, s.contact.dhat, source.string());
  }
  return s;
}

Scene load_scene(const std::filesystem::path& file) {
  if (const std::string problem = input_file_problem(file, "scene file"); !problem.empty()) throw SceneError(problem);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(fmt::format("{}: cannot open the scene file", file.string()));
  // Read up to the first NUL byte, which JSON text never holds: a NUL-padded file fails having read about
  // as much as its text.
  std::string text;
  for (std::size_t old = 0;; old = text.size()) {
    text.resize(old + (1 << 20));
    in.read(text.data() + old, 1 << 20);
    text.resize(old + static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw SceneError(fmt::format("{}: cannot read the scene file", file.string()));
    if (text.size() == old || text.find('\0', old) != std::string::npos) break;
  }
  return parse_scene(read_scene_json(text, file.string()), file);
}

std::shared_ptr<const SceneMesh> scene_mesh(const Scene& s) {
  if (s.loaded) return s.loaded;
  auto out = std::make_shared<SceneMesh>();
  if (s.flesh) {
    auto flesh = std::make_shared<Flesh>(build_flesh(*s.flesh, s.source.string()));
    out->mesh = flesh->volume;
    out->digest = file_digest(s.flesh->model);
    out->flesh = std::move(flesh);
    return out;
  }
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
  if (const std::shared_ptr<const Flesh> flesh = scene_mesh(s)->flesh) sets.push_back(bone_kinematics(flesh));
  return sets;
}

namespace {

std::string frame_name(int index) { return fmt::format("{:03d}.obj", index); }

/// A flesh run's own output: its settings and header lines, the render surface's volumes in the records,
/// surface/NNN.obj and lbs/NNN.obj every frame, and flesh.usda at the end (from the frames on disk, so that
/// a resumed run's stage holds them all).
void add_flesh_output(const Flesh& flesh, const Scene& s, const Simulation& sim, RunPlan& plan) {
  const FleshSpec& spec = *s.flesh;
  const RiggedModel& m = flesh.model;
  plan.table = &flesh_table();
  json bones = json::array();
  for (std::size_t b = 0; b < flesh.bones.size(); ++b)
    bones.push_back({{"name", flesh.bones[b].name}, {"radius", flesh.bones[b].radius}, {"bound", flesh.bound_per_bone[b]}});
  plan.settings["model"] = spec.model.string();
  plan.settings["volume"] = spec.volume == FleshVolume::lattice ? "lattice" : "tets";
  plan.settings["resolution"] = spec.resolution;
  plan.settings["animation"] = flesh.clip.name;
  plan.settings["model_vertices"] = m.vertices.cols();
  plan.settings["model_triangles"] = m.triangles.cols();
  plan.settings["joints"] = m.skeleton.size();
  plan.settings["bound_vertices"] = flesh.binding.vertex.size();
  plan.settings["volume_of_cells"] = flesh.volume_of_cells;
  plan.settings["surface_volume"] = flesh.surface_volume;
  plan.settings["bones"] = bones;
  plan.settings["joint_cells"] = to_string(spec.joint_cells);
  plan.settings["released_vertices"] = flesh.released.vertex.size();
  if (spec.soft_shell > 0.0)
    plan.settings["soft_binding"] = {{"shell", spec.soft_shell}, {"stiffness", spec.soft_stiffness}, {"vertices", flesh.soft.vertex.size()}};
  const double rest_surface = surface_volume(flesh, m.vertices);

  const auto base_header = plan.header;
  plan.header = [&flesh, &spec, base_header](std::ostream& o) {
    const RiggedModel& m = flesh.model;
    o << fmt::format("model {}: {} vertices ({} welded), {} triangles, {} joints (hierarchy from the {}), animation \"{}\" "
                     "of {:g} s\n",
                     m.source.string(), m.vertices.cols(), m.surface_vertices.cols(), m.triangles.cols(), m.skeleton.size(),
                     m.hierarchy == "names" ? "joint names" : "file", flesh.clip.name, flesh.clip.duration());
    o << fmt::format("volume: {} at resolution {} ({} {:.4g} wide): {} cells, {} vertices; volume {:.6g} against the surface's "
                     "{:.6g} ({:.3f}x)\n",
                     spec.volume == FleshVolume::lattice ? "hexahedral lattice" : "tets (TetGen)", spec.resolution,
                     spec.volume == FleshVolume::lattice ? "cubes" : "tets no larger than a sixth of a cube",
                     flesh.cell_size, flesh.volume.cell_count(), flesh.volume.vertex_count(), flesh.volume_of_cells,
                     flesh.surface_volume, flesh.volume_of_cells / flesh.surface_volume);
    std::string counts;
    for (std::size_t b = 0; b < flesh.bones.size(); ++b)
      counts += fmt::format("{}{} {}", b ? ", " : "", flesh.bones[b].name, flesh.bound_per_bone[b]);
    o << fmt::format("bones: {} binding {} volume vertices ({})\n", flesh.bones.size(), flesh.binding.vertex.size(), counts);
    if (!flesh.released.vertex.empty())
      o << fmt::format("joints: {} vertices of capsules in cells spanning two joints {} (joint cells {})\n", flesh.released.vertex.size(),
                       spec.joint_cells == JointCells::soft ? "bound softly instead" : "released", to_string(spec.joint_cells));
    if (spec.soft_shell > 0.0)
      o << fmt::format("soft binding: {} more volume vertices within {:.4g} of the capsules, pulled by springs of {:g} x E x h "
                       "(fading to 0 at the shell's edge)\n",
                       flesh.soft.vertex.size(), spec.soft_shell, spec.soft_stiffness);
    for (std::size_t b = 0; b < flesh.bones.size(); ++b)
      if (flesh.bound_per_bone[b] == 0)
        o << fmt::format("warning: bone {} binds no volume vertex (capsule radius {:.4g}; cells {:.4g} wide)\n", flesh.bones[b].name,
                         flesh.bones[b].radius, flesh.cell_size);
    if (base_header) base_header(o);
  };
  const auto base_fill = plan.fill;
  plan.fill = [&flesh, &sim, rest_surface, base_fill](StepRecord& r, const StepReport* rep) {
    if (base_fill) base_fill(r, rep);
    r.surface_volume_ratio = surface_volume(flesh, flesh_surface(flesh, sim.x())) / rest_surface;
    r.lbs_volume_ratio = surface_volume(flesh, skinned_surface(flesh, r.time)) / rest_surface;
  };
  const std::filesystem::path out = plan.out;
  plan.write_frame = [&flesh, out](int index, double time, const Eigen::VectorXd& x) {
    ensure_writable_directory(out / "surface");
    ensure_writable_directory(out / "lbs");
    write_obj(out / "surface" / frame_name(index), flesh_surface(flesh, x), flesh.model.triangles);
    write_obj(out / "lbs" / frame_name(index), skinned_surface(flesh, time), flesh.model.triangles);
  };
  const double fps = s.time.frames / s.time.end_time;
  plan.finish = [&flesh, out, fps](json& stats) {
    std::vector<UsdMesh> meshes{{.name = "flesh", .triangles = flesh.model.triangles, .frames = {}},
                                {.name = "linear_blend_skinning", .triangles = flesh.model.triangles, .frames = {}}};
    for (int i = 0; std::filesystem::exists(out / "surface" / frame_name(i)) && std::filesystem::exists(out / "lbs" / frame_name(i)); ++i) {
      meshes[0].frames.push_back(read_surface(out / "surface" / frame_name(i)).vertices);
      meshes[1].frames.push_back(read_surface(out / "lbs" / frame_name(i)).vertices);
    }
    if (meshes[0].frames.empty()) return;
    write_usda(out / "flesh.usda", "character", meshes, fps);
    stats["usd"] = "flesh.usda";
    // The bones at every frame written, for the report: segment ends in world space.
    json names = json::array(), frames = json::array();
    for (const Bone& b : flesh.bones) names.push_back(b.name);
    for (std::size_t i = 0; i < meshes[0].frames.size(); ++i) {
      const double t = static_cast<double>(i) / fps;
      const std::vector<Eigen::Affine3d> world = joint_world(flesh, t);
      json segments = json::array();
      for (const Bone& b : flesh.bones) {
        const Eigen::Vector3d a = world[b.joint] * (flesh.rest_world[b.joint].inverse() * b.a);
        const Eigen::Vector3d c = world[b.joint] * (flesh.rest_world[b.joint].inverse() * b.b);
        segments.push_back({a[0], a[1], a[2], c[0], c[1], c[2]});
      }
      frames.push_back({{"time", t}, {"segments", segments}});
    }
    write_atomically(out / "bones.json", [&](std::ostream& o) { o << json{{"bones", names}, {"frames", frames}}.dump() << "\n"; });
  };
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
    r.ccd_calls = static_cast<int>(c.ccd_calls);
    r.ccd_tests = static_cast<int>(std::min<long long>(c.ccd_tests, std::numeric_limits<int>::max()));
    r.contact_seconds = c.seconds;
  };
  const auto base_line = plan.line;
  plan.line = [base_line](const StepRecord& r) {
    return base_line(r) + (r.contact_pairs > 0 ? fmt::format(", {} contact pairs, min distance {:.3g}", r.contact_pairs,
                                                             r.min_contact_distance)
                                               : std::string(", no contact pairs"));
  };
}

}  // namespace

SceneResult run_scene(const Scene& s, std::ostream& log) {
  if (s.output.dir.empty()) throw SceneError(fmt::format("{}: no output directory", s.source.string()));
  const std::shared_ptr<const SceneMesh> loaded = scene_mesh(s);
  const VolumeMesh& mesh = loaded->mesh;
  const Eigen::VectorXd x0 = initial_positions(s, mesh);
  const bool dynamic = s.time.integrator == Integrator::backward_euler;
  const double frame_dt = s.time.end_time / s.time.frames;
  const int substeps = checked_substeps(s.time, s.source.string());
  const double h = frame_dt / substeps;

  SimulationSetup setup;
  setup.mesh = mesh;
  setup.materials = {make_material(s.material.name, s.material.params, s.material.reparametrize)};
  setup.density = s.material.density;
  setup.integrator = s.time.integrator;
  setup.extrapolation = 2;
  setup.dt = h;
  setup.gravity = s.forces.gravity;
  setup.mass_damping = s.forces.mass_damping;
  setup.stiffness_damping = s.forces.stiffness_damping;
  setup.kinematic = scene_kinematics(s, mesh, x0);
  if (loaded->flesh && !dynamic) setup.carrier = flesh_carrier(loaded->flesh);  // guesses that follow the bones
  if (loaded->flesh)
    if (std::shared_ptr<Term> soft = soft_binding_term(loaded->flesh, s.flesh->soft_stiffness, youngs_modulus(s.material.params)))
      setup.terms.push_back(std::move(soft));
  double kappa = s.contact.stiffness;
  int bone_colliders = 0;     // a flesh's bones with a capsule collider
  double slip_velocity = 0.0;  // friction's ε_v
  if (s.contact.enabled) {
    if (kappa == 0.0) {  // "auto": IPC's choice on the mesh's size, its average vertex mass and the substep
      const Eigen::Matrix3Xd& X = mesh.vertices;
      const double diagonal = (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
      const double mass = s.material.density * std::abs(mesh_volume(mesh)) / static_cast<double>(mesh.vertex_count());
      kappa = as_scene_error([&] { return ipc_barrier_stiffness(diagonal, s.contact.dhat, mass, h); });
    }
    slip_velocity = s.contact.friction_velocity > 0.0 ? s.contact.friction_velocity
                                                      : 1e-3 * (mesh.vertices.rowwise().maxCoeff() - mesh.vertices.rowwise().minCoeff()).norm();
    // On the volume's boundary, or on a flesh's render surface embedded in the volume.
    const ContactSurface surface = loaded->flesh ? skin_contact_surface(*loaded->flesh) : boundary_contact_surface(mesh);
    std::vector<std::shared_ptr<Term>> bones;
    if (loaded->flesh && s.contact.bones) bones = bone_collider_terms(loaded->flesh, s.contact.dhat, kappa);
    bone_colliders = static_cast<int>(bones.size());
    for (std::shared_ptr<Term>& t :
         contact_terms(s.contact, surface, mesh.vertices, {s.contact.dhat, kappa, s.contact.friction, slip_velocity}, std::move(bones)))
      setup.terms.push_back(std::move(t));
  }
  setup.initial = x0;
  setup.linear.name = s.solver.linear;
  setup.linear.reuse_factor = !s.solver.refactorize;
  setup.newton = newton_options(s.solver, mesh, youngs_modulus(s.material.params));
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
  settings["solver"] = std::string(sim.solver().name());  // what "auto" chose
  settings["tolerance"] = sim.setup().newton.tolerance;
  settings["step_tolerance"] = sim.setup().newton.step_tolerance;
  settings["relative_step_tolerance"] = sim.setup().newton.relative_step_tolerance;
  settings["vertices"] = result.vertices;
  settings["cells"] = result.cells;
  if (s.contact.enabled) {
    json planes = json::array();
    for (const PlaneColliderSpec& p : s.contact.planes)
      planes.push_back({{"point", {p.point[0], p.point[1], p.point[2]}}, {"normal", {p.normal[0], p.normal[1], p.normal[2]}}});
    settings["contact"] = {{"self", s.contact.self}, {"dhat", s.contact.dhat}, {"stiffness", kappa},
                           {"stiffness_auto", s.contact.stiffness == 0.0}, {"planes", planes},
                           {"colliders", s.contact.planes.size() + s.contact.colliders.size()}, {"friction", s.contact.friction}};
    if (s.contact.friction > 0.0) settings["contact"]["friction_velocity"] = slip_velocity;
    if (loaded->flesh) settings["contact"]["bone_colliders"] = bone_colliders;
  }

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
    o << fmt::format("{}, {} frames to t = {:g}{}, gravity ({:g}, {:g}, {:g}), solver {} ({}), output {}\n",
                     dynamic ? "backward Euler" : "quasi-static", s.time.frames, s.time.end_time,
                     dynamic ? fmt::format(" ({} substeps of {:g} per frame)", substeps, h) : "", s.forces.gravity[0],
                     s.forces.gravity[1], s.forces.gravity[2],
                     s.solver.linear == "auto" ? fmt::format("{} (auto)", sim.solver().name()) : s.solver.linear,
                     stopping_rule(sim.setup().newton),
                     s.output.dir.string());
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

  if (const std::shared_ptr<const Flesh> flesh = loaded->flesh) add_flesh_output(*flesh, s, sim, plan);
  if (std::any_of(sim.problem().terms().begin(), sim.problem().terms().end(), [](const Term* t) { return t->reports_contact(); }))
    add_contact_statistics(sim, plan);
  if (s.run.check_only) {
    plan.header(log);
    log << fmt::format("checked: {} {}, {} vertices, {} free DOFs; no frame run\n", mesh.cell_count(), cells, mesh.vertex_count(),
                       sim.problem().dofs().free_count());
    result.all_converged = true;
    return result;
  }

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
