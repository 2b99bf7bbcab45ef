#include "snh/setup/scene_build.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include <fmt/format.h>

#include "snh/fem/contact_term.hpp"
#include "snh/io/checksum.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/material/registry.hpp"
#include "snh/setup/flesh_scene.hpp"
#include "snh/setup/scene/sections.hpp"

namespace snh {
namespace {

Eigen::Vector3d centre_of(const Eigen::Matrix3Xd& X) { return 0.5 * (X.rowwise().minCoeff() + X.rowwise().maxCoeff()); }

constexpr double max_substeps_in_run = 1e8;  ///< substeps a run may take in all (issue 13)

/// Substeps per frame (dynamic integrators split a frame into equal substeps no longer than dt; quasi-static: one),
/// computed in double so that no count overflows; a run that cannot be done (over 1e8 substeps in all, over
/// 100000 frames) is a SceneError naming the file and the value at fault.
int checked_substeps(const TimeSpec& t, double end_time, int frames, const std::string& file) {
  if (frames < 1 || frames > TimeSpec::max_frames)
    throw SceneError(fmt::format("{}: frames: must be from 1 to {}, got {}", file, TimeSpec::max_frames, frames));
  if (!(end_time > 0.0) || !std::isfinite(end_time))
    throw SceneError(fmt::format("{}: end_time: must be a finite number > 0, got {:g}", file, end_time));
  if (!is_dynamic(t.integrator)) return 1;
  if (!(t.dt > 0.0) || !std::isfinite(t.dt)) throw SceneError(fmt::format("{}: dt: must be a finite number > 0, got {:g}", file, t.dt));
  const double per_frame = std::max(1.0, std::ceil(end_time / frames / t.dt - 1e-9));
  const double total = per_frame * frames;
  if (!(total <= max_substeps_in_run))
    throw SceneError(fmt::format("{}: dt: {:g} with end_time {:g} over {} frames makes {:.3g} substeps; at most {:g} can run "
                                 "(raise dt or lower end_time)",
                                 file, t.dt, end_time, frames, total, max_substeps_in_run));
  return static_cast<int>(per_frame);
}

/// Two pin sets may share a vertex, each holding its own coordinates; a moving set must then not move the
/// vertex along a coordinate that the other set holds elsewhere (a rotation about z, say, while another set holds
/// y still): the two would drive the vertex in different ways. Checked at the motions' starts, ends and
/// in between; `sets` are the scene's kinematic sets (its pins first).
void check_shared_pins(const Scene& s, double end_time, const std::vector<KinematicSet>& sets) {
  const std::size_t pins = s.pins.size();
  if (pins < 2) return;
  std::vector<double> times{0.0, end_time};
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

/// Coordinates in range: a mesh file's (a box's are, from its checked corners), then after the initial
/// operations.
void check_coordinates(const Scene& s, const VolumeMesh& mesh, const Eigen::VectorXd& x0) {
  const Eigen::Matrix3Xd& X = mesh.vertices;
  for (Eigen::Index v = 0; v < X.cols(); ++v)
    for (int a = 0; a < 3; ++a)
      if (!(std::abs(X(a, v)) <= scene::max_magnitude))
        throw SceneError(fmt::format("{}: {}: vertex {} has coordinate {:g}, beyond the {:g} a scene allows", s.source.string(),
                                     s.mesh.file.empty() ? std::string("mesh") : "mesh.file " + s.mesh.file.string(), v, X(a, v),
                                     scene::max_magnitude));
  if (!(x0.array().abs() <= scene::max_magnitude).all())
    throw SceneError(fmt::format("{}: initial: the operations move a vertex beyond the {:g} a scene allows (largest coordinate {:g})",
                                 s.source.string(), scene::max_magnitude, x0.array().abs().maxCoeff()));
}

/// The cells' size: the cube root of their mean rest volume.
double mean_cell_size(const VolumeMesh& mesh) {
  return std::cbrt(std::abs(mesh_volume(mesh)) / static_cast<double>(mesh.cell_count()));
}

/// Contact's parameters for a volume scene: d̂ as given, κ as given, else chosen: when dynamic, IPC's
/// automatic choice on the mesh's size, its average vertex mass and the substep; quasi-statically (no masses,
/// no time step) the elastic rule the flesh uses, κ = E ℓ / d̂² (ℓ the cube root of the mean cell volume: a
/// barrier about as stiff as a cell of the material where surfaces come within d̂). `how` says which.
ContactParameters volume_contact(const Scene& s, const VolumeMesh& mesh, double substep, std::string& how) {
  ContactParameters p;
  p.dhat = s.contact.dhat.value_or(0.0);  // required by the parser
  if (s.contact.stiffness) {
    p.stiffness = *s.contact.stiffness;
    how = "given";
  } else if (is_dynamic(s.time.integrator)) {
    const Eigen::Matrix3Xd& X = mesh.vertices;
    const double diagonal = (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
    const double mass = s.material.density * std::abs(mesh_volume(mesh)) / static_cast<double>(mesh.vertex_count());
    p.stiffness = scene::as_scene_error([&] { return ipc_barrier_stiffness(diagonal, p.dhat, mass, substep); });
    how = "chosen by IPC's rule on the mesh's size, mass and time step";
  } else {
    p.stiffness = youngs_modulus(s.material.params) * mean_cell_size(mesh) / (p.dhat * p.dhat);
    how = "chosen as E l / dhat^2, l the cells' size";
  }
  return p;
}

}  // namespace

NewtonOptions newton_options(const SolverSpec& solver, const VolumeMesh& rest, double youngs) {
  NewtonOptions o = solver.newton;
  o.tolerance = solver.tolerance.value_or(0.0);
  o.step_tolerance = solver.step_tolerance.value_or(0.0);
  if (o.tolerance == 0.0 && solver.force_fraction > 0.0 && rest.cell_count() > 0) {
    const double cell = mean_cell_size(rest);
    o.tolerance = solver.force_fraction * youngs * cell * cell;
  }
  return o;
}

std::shared_ptr<const SceneBody> scene_body(const Scene& s) {
  auto out = std::make_shared<SceneBody>();
  if (s.flesh) {
    auto flesh = std::make_shared<Flesh>(build_flesh(*s.flesh, s.source.string(), s.solver.linear));
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
    out->cell_tags = std::move(f.cell_tags);
    out->digest = file_digest(m.file);
    return out;
  }
  out->mesh = m.element == CellType::tet4 ? box_tets(m.resolution, m.tet_split) : box_hexes(m.resolution);
  // [−1, 1]³ → [min, max]
  const Eigen::Vector3d half = 0.5 * (m.max - m.min), mid = 0.5 * (m.max + m.min);
  out->mesh.vertices = (half.asDiagonal() * out->mesh.vertices).colwise() + mid;
  return out;
}

BuiltScene build_scene(const Scene& s) {
  const std::string file = s.source.string();
  BuiltScene b;
  b.scene = s;
  for (ColliderSpec& c : b.scene.contact.colliders)
    if (c.type == ColliderSpec::Type::mesh) scene::read_collider_mesh(c, file);
  // Time: a volume scene's is checked before its mesh is read (a flesh's clip may set the end time).
  b.end_time = s.time.end_time.value_or(TimeSpec::default_end_time);
  b.frames = s.time.frames.value_or(TimeSpec::default_frames);
  if (!s.flesh) b.substeps = checked_substeps(s.time, b.end_time, b.frames, file);
  b.body = scene::as_scene_error([&] { return scene_body(b.scene); });
  const VolumeMesh& mesh = b.body->mesh;
  const double youngs = youngs_modulus(s.material.params);
  if (const Flesh* flesh = b.body->flesh.get()) {
    flesh_time(s, *flesh, b.end_time, b.frames);
    b.substeps = checked_substeps(s.time, b.end_time, b.frames, file);
    b.newton = flesh_newton_options(s.solver, *flesh, s.material.params);
  } else {
    b.newton = newton_options(s.solver, mesh, youngs);
  }
  b.substep = b.end_time / b.frames / b.substeps;
  if (s.contact.enabled) {
    if (b.body->flesh) {
      b.contact = flesh_contact(s.contact, *b.body->flesh, youngs);
      b.contact_stiffness_rule = s.contact.stiffness ? "given" : "chosen as E h / dhat^2, h the cell size";
    } else {
      b.contact = volume_contact(s, mesh, b.substep, b.contact_stiffness_rule);
    }
    b.contact.friction = s.contact.friction;
    b.contact.slip_velocity = s.contact.friction_velocity
                                  ? *s.contact.friction_velocity
                                  : 1e-3 * (mesh.vertices.rowwise().maxCoeff() - mesh.vertices.rowwise().minCoeff()).norm();
  }
  // The pins must select something on the body and hold each coordinate once; contact needs a separated start.
  b.x0 = initial_positions(s, mesh);
  b.v0 = initial_velocities(s, mesh);
  check_coordinates(s, mesh, b.x0);
  b.muscles = scene::as_scene_error([&] { return build_muscles(s, *b.body); });  // a joint the model lacks: RigError
  std::vector<KinematicSet> sets = scene::as_scene_error([&] { return scene_kinematics(s, *b.body, b.x0); });
  if (b.muscles) sets.insert(sets.end(), b.muscles->bones.begin(), b.muscles->bones.end());
  (void)scene::as_scene_error([&] { return kinematic_dof_flags(sets, mesh.vertex_count()); });
  check_shared_pins(s, b.end_time, sets);
  if (s.contact.enabled)
    check_contact_start(b.scene.contact, contact_surface_of(*b.body), mesh.vertices, b.x0, b.contact.dhat, file);
  return b;
}

ContactSurface contact_surface_of(const SceneBody& body) {
  return body.flesh ? skin_contact_surface(*body.flesh) : boundary_contact_surface(body.mesh);
}

SimulationSetup simulation_setup(const BuiltScene& b) {
  const Scene& s = b.scene;
  const VolumeMesh& mesh = b.body->mesh;
  SimulationSetup setup;
  setup.mesh = mesh;
  setup.materials = {make_material(s.material.name, s.material.params, s.material.reparametrize)};
  setup.density = s.material.density;
  setup.integrator = s.time.integrator;
  setup.extrapolation = 2;
  setup.dt = b.substep;
  setup.gravity = s.forces.gravity;
  setup.mass_damping = s.forces.mass_damping;
  setup.stiffness_damping = s.forces.stiffness_damping;
  setup.kinematic = scene_kinematics(s, *b.body, b.x0);
  if (const std::shared_ptr<const BuiltMuscles>& m = b.muscles) {
    setup.materials = m->materials;
    setup.material_of_cell = m->material_of_cell;
    setup.fibre_of_cell = m->fibre_of_cell;
    setup.fibres = m->fibres;
    if (!m->muscles.empty()) setup.fibre_strain = [m](double t, std::vector<double>& alpha) { m->fibre_strain(t, alpha); };
    setup.kinematic.insert(setup.kinematic.end(), m->bones.begin(), m->bones.end());
  }
  std::vector<std::shared_ptr<Term>> bones;  // a flesh's bones against its skin, among the contact terms
  if (b.body->flesh) add_flesh_terms(b, setup, bones);
  if (s.contact.enabled)
    for (std::shared_ptr<Term>& t : contact_terms(s.contact, contact_surface_of(*b.body), mesh.vertices, b.contact, std::move(bones)))
      setup.terms.push_back(std::move(t));
  setup.initial = b.x0;
  if (!b.v0.isZero(0.0)) setup.initial_velocity = b.v0;
  setup.linear.name = s.solver.linear;
  setup.linear.reuse_factor = !s.solver.refactorize;
  setup.step_halvings = s.solver.step_halvings;
  setup.newton = b.newton;
  return setup;
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
          } else if constexpr (std::is_same_v<Op, MoveOp>) {
            for (int v : select_vertices(op.select, X, fmt::format("{}: initial[{}]", s.source.string(), i))) X.col(v) += op.by;
          }  // VelocityOp: initial_velocities
        },
        s.initial[i]);
  return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
}

Eigen::VectorXd initial_velocities(const Scene& s, const VolumeMesh& mesh) {
  Eigen::Matrix3Xd V = Eigen::Matrix3Xd::Zero(3, mesh.vertex_count());
  for (std::size_t i = 0; i < s.initial.size(); ++i) {
    const auto* op = std::get_if<VelocityOp>(&s.initial[i]);
    if (!op) continue;
    const std::string where = fmt::format("{}: initial[{}]", s.source.string(), i);
    if (!is_dynamic(s.time.integrator))
      throw SceneError(fmt::format("{}: a velocity needs a dynamic integrator (backward_euler, bdf2 or tr_bdf2), not {}", where,
                                   integrator_name(s.time.integrator)));
    if (!op->select) V.colwise() += op->value;
    else
      for (int v : select_vertices(*op->select, mesh.vertices, where)) V.col(v) += op->value;
  }
  return Eigen::Map<const Eigen::VectorXd>(V.data(), V.size());
}

std::vector<KinematicSet> scene_kinematics(const Scene& s, const SceneBody& body, const Eigen::VectorXd& x0) {
  const VolumeMesh& mesh = body.mesh;
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
  if (body.flesh) sets.push_back(bone_kinematics(body.flesh));
  return sets;
}

}  // namespace snh
