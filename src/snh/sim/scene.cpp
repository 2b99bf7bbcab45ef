#include "snh/sim/scene.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/material/registry.hpp"
#include "snh/sim/dynamics.hpp"
#include "snh/sim/checkpoint.hpp"
#include "snh/sim/interrupt.hpp"
#include "snh/sim/output.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

/// Reads the keys of one JSON object, remembering which were used, so that unknown keys can be named.
class Keys {
 public:
  Keys(const json& j, std::string path, const std::string& file) : j_(j), path_(std::move(path)), file_(file) {
    if (!j.is_object()) fail("expected an object");
  }
  [[noreturn]] void fail(const std::string& what, const std::string& key = "") const {
    const std::string where = key.empty() ? path_ : (path_.empty() ? key : path_ + "." + key);
    throw SceneError(fmt::format("{}: {}{}", file_, where.empty() ? "" : where + ": ", what));
  }
  std::string path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  const json* get(const std::string& key) {
    used_.insert(key);
    const auto it = j_.find(key);
    return it == j_.end() ? nullptr : &*it;
  }
  bool has(const std::string& key) const { return j_.contains(key); }
  double number(const std::string& key, double fallback) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_number() || !std::isfinite(v->get<double>())) fail("expected a finite number, got " + v->dump(), key);
    return v->get<double>();
  }
  double positive(const std::string& key, double fallback) {
    const double v = number(key, fallback);
    if (!(v > 0.0)) fail(fmt::format("must be > 0, got {:g}", v), key);
    return v;
  }
  double non_negative(const std::string& key, double fallback) {
    const double v = number(key, fallback);
    if (!(v >= 0.0)) fail(fmt::format("must be >= 0, got {:g}", v), key);
    return v;
  }
  long long integer(const std::string& key, long long fallback, long long lo, long long hi) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_number_integer()) fail("expected an integer, got " + v->dump(), key);
    const long long n = v->get<long long>();
    if (n < lo || n > hi) fail(fmt::format("must be from {} to {}, got {}", lo, hi, n), key);
    return n;
  }
  bool boolean(const std::string& key, bool fallback) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_boolean()) fail("expected true or false, got " + v->dump(), key);
    return v->get<bool>();
  }
  std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) {
    const json* v = get(key);
    if (!v) return fallback;
    if (!v->is_string() || std::find(allowed.begin(), allowed.end(), v->get<std::string>()) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(fmt::format("expected one of {}, got {}", list, v->dump()), key);
    }
    return v->get<std::string>();
  }
  std::optional<Eigen::Vector3d> vec3(const std::string& key) {
    const json* v = get(key);
    if (!v) return std::nullopt;
    if (!v->is_array() || v->size() != 3) fail("expected 3 numbers, got " + v->dump(), key);
    Eigen::Vector3d out;
    for (int i = 0; i < 3; ++i) {
      if (!(*v)[i].is_number() || !std::isfinite((*v)[i].get<double>())) fail("expected 3 finite numbers, got " + v->dump(), key);
      out[i] = (*v)[i].get<double>();
    }
    return out;
  }
  /// An axis: "x", "y" or "z".
  int axis(const std::string& key, const std::string& fallback) {
    const std::string a = choice(key, fallback, {"x", "y", "z"});
    return a[0] - 'x';
  }
  /// Throws for the first key that was never asked for.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it)
      if (!used_.count(it.key())) {
        std::string known;
        for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
        fail(fmt::format("unknown key (known here: {})", known), it.key());
      }
  }

 private:
  const json& j_;
  std::string path_, file_;
  std::set<std::string> used_;
};

Selection parse_selection(Keys& k, const std::string& file) {
  Selection s;
  const json* region = k.get("region");
  const json* indices = k.get("indices");
  if ((region != nullptr) == (indices != nullptr)) k.fail("give exactly one of region or indices");
  if (region) {
    Keys r(*region, k.path("region"), file);
    const auto lo = r.vec3("min"), hi = r.vec3("max");
    if (!lo || !hi) r.fail("needs min and max");
    if ((lo->array() > hi->array()).any()) r.fail("min must not exceed max");
    r.finish();
    s.region = Eigen::AlignedBox3d(*lo, *hi);
  } else {
    if (!indices->is_array() || indices->empty()) k.fail("expected a non-empty array of vertex indices", "indices");
    for (const auto& i : *indices) {
      if (!i.is_number_integer() || i.get<long long>() < 0 || i.get<long long>() > std::numeric_limits<int>::max())
        k.fail("expected vertex indices (integers >= 0), got " + i.dump(), "indices");
      s.indices.push_back(i.get<int>());
    }
  }
  return s;
}

Motion parse_motion(const json& j, const std::string& path, const std::string& file, double end_time) {
  Keys k(j, path, file);
  Motion m;
  const std::string type = k.choice("type", "", {"translate", "rotate", "scale"});
  if (type.empty()) k.fail("needs a type (translate, rotate or scale)");
  m.start = k.non_negative("start", 0.0);
  m.end = k.non_negative("end", end_time);
  if (!(m.end > m.start)) k.fail(fmt::format("end ({:g}) must be later than start ({:g})", m.end, m.start));
  m.center = k.vec3("center");
  if (type == "translate") {
    m.kind = Motion::Kind::translate;
    const auto by = k.vec3("by");
    if (!by) k.fail("translate needs by: [dx, dy, dz]");
    m.vector = *by;
  } else if (type == "rotate") {
    m.kind = Motion::Kind::rotate;
    const auto axis = k.vec3("axis");
    if (!axis || axis->norm() == 0.0) k.fail("rotate needs a non-zero axis: [ax, ay, az]");
    m.vector = axis->normalized();
    m.angle = k.number("degrees", 0.0) * std::numbers::pi / 180.0;
  } else {
    m.kind = Motion::Kind::scale;
    const auto f = k.vec3("factors");
    if (!f || (f->array() <= 0.0).any()) k.fail("scale needs factors: three numbers > 0");
    m.vector = *f;
  }
  k.finish();
  return m;
}

InitialOp parse_initial(const json& j, const std::string& path, const std::string& file) {
  Keys k(j, path, file);
  InitialOp op;
  const std::string type = k.choice("type", "", {"scale", "reflect", "collapse", "perturb", "move"});
  if (type.empty()) k.fail("needs a type (scale, reflect, collapse, perturb or move)");
  if (type != "perturb" && type != "move") op.center = k.vec3("center");
  if (type == "scale") {
    op.kind = InitialOp::Kind::scale;
    const auto f = k.vec3("factors");
    if (!f) k.fail("scale needs factors: [sx, sy, sz]");
    op.vector = *f;
  } else if (type == "reflect") {
    op.kind = InitialOp::Kind::reflect;
    op.axis = k.axis("axis", "x");
  } else if (type == "collapse") {
    op.kind = InitialOp::Kind::collapse;
    const std::string to = k.choice("to", "point", {"plane", "line", "point"});
    op.to = to == "plane" ? InitialOp::To::plane : to == "line" ? InitialOp::To::line : InitialOp::To::point;
    op.axis = k.axis("axis", "y");
  } else if (type == "perturb") {
    op.kind = InitialOp::Kind::perturb;
    op.amplitude = k.non_negative("amplitude", 0.0);
    op.seed = static_cast<std::uint64_t>(k.integer("seed", 1, 0, std::numeric_limits<long long>::max()));
  } else {
    op.kind = InitialOp::Kind::move;
    op.select = parse_selection(k, file);
    const auto by = k.vec3("by");
    if (!by) k.fail("move needs by: [dx, dy, dz]");
    op.vector = *by;
  }
  k.finish();
  return op;
}

/// Vertices of the selection (checked against the vertex count).
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

Eigen::Vector3d centre_of(const Eigen::Matrix3Xd& X) {
  return 0.5 * (X.rowwise().minCoeff() + X.rowwise().maxCoeff());
}

/// The positions of a pin set at time t: its base positions moved by each motion in turn.
Eigen::Matrix3Xd pin_targets(const PinSet& pin, const Eigen::Matrix3Xd& base, double t) {
  Eigen::Matrix3Xd P = base;
  for (const Motion& m : pin.motions) {
    const double p = std::clamp((t - m.start) / (m.end - m.start), 0.0, 1.0);
    const Eigen::Vector3d c = m.center.value_or(P.rowwise().mean());
    switch (m.kind) {
      case Motion::Kind::translate: P.colwise() += p * m.vector; break;
      case Motion::Kind::rotate: {
        const Eigen::Matrix3d R = Eigen::AngleAxisd(p * m.angle, m.vector).toRotationMatrix();
        P = (R * (P.colwise() - c)).colwise() + c;
        break;
      }
      case Motion::Kind::scale: {
        const Eigen::Vector3d f = Eigen::Vector3d::Ones() + p * (m.vector - Eigen::Vector3d::Ones());
        P = (f.asDiagonal() * (P.colwise() - c)).colwise() + c;
        break;
      }
    }
  }
  return P;
}

using Clock = std::chrono::steady_clock;

/// The first `count` frames' stats of DIR/stats.json (a resumed run's history).
std::vector<FrameStats> read_frames(const std::filesystem::path& dir, int count) {
  auto num = [](const json& f, const char* key) {
    const auto it = f.find(key);
    return it == f.end() || !it->is_number() ? std::numeric_limits<double>::quiet_NaN() : it->get<double>();
  };
  std::vector<FrameStats> out;
  for (const auto& f : history_for_resume(dir, "frames", count)) {
    FrameStats s;
    s.frame = f.value("frame", 0);
    s.time = num(f, "time");
    s.substeps = f.value("substeps", 0);
    s.converged = f.value("converged", false);
    s.newton_iterations = f.value("newton_iterations", 0);
    s.line_search_steps = f.value("line_search_steps", 0);
    s.linear_iterations = f.value("linear_iterations", 0);
    s.factorizations = f.value("factorizations", 0);
    s.residual = num(f, "residual");
    s.elastic_energy = num(f, "elastic_energy");
    s.kinetic_energy = num(f, "kinetic_energy");
    s.gravity_energy = num(f, "gravity_energy");
    s.total_energy = num(f, "total_energy");
    s.volume_ratio = num(f, "volume_ratio");
    s.min_J = num(f, "min_J");
    s.inverted = f.value("inverted", 0);
    s.wall_seconds = num(f, "wall_seconds");
    s.failure = f.value("failure", std::string());
    out.push_back(s);
  }
  return out;
}

void write_scene_stats(const Scene& s, const SceneResult& r) {
  json j;
  j["program"] = "snh run";
  if (!s.command_line.empty()) j["command_line"] = s.command_line;
  j["snh_version"] = SNH_VERSION;
  j["scene"] = s.source.string();
  j["element"] = std::string(to_string(r.element));
  if (s.mesh_file.empty()) j["resolution"] = s.resolution;
  else j["mesh_file"] = s.mesh_file.string();
  j["material"] = s.material;
  j["mu"] = s.params.mu;
  j["lambda"] = s.params.lambda;
  j["reparametrize"] = s.reparametrize;
  j["density"] = s.density;
  j["integrator"] = s.integrator == Integrator::backward_euler ? "backward_euler" : "quasi_static";
  j["dt"] = s.dt;
  j["end_time"] = s.end_time;
  j["gravity"] = {s.gravity[0], s.gravity[1], s.gravity[2]};
  j["mass_damping"] = s.mass_damping;
  j["stiffness_damping"] = s.stiffness_damping;
  j["solver"] = s.solver;
  j["tolerance"] = s.newton.tolerance;
  j["vertices"] = r.vertices;
  j["cells"] = r.cells;
  j["all_converged"] = r.all_converged;
  j["failure"] = r.failure;
  j["interrupted_by_signal"] = r.interrupted_by;
  j["total_seconds"] = r.total_seconds;
  j["peak_memory_mib"] = r.peak_memory_mib;
  json frames = json::array();
  for (const FrameStats& f : r.frames)
    frames.push_back({{"frame", f.frame}, {"time", f.time}, {"substeps", f.substeps}, {"converged", f.converged},
                      {"newton_iterations", f.newton_iterations}, {"line_search_steps", f.line_search_steps},
                      {"linear_iterations", f.linear_iterations}, {"factorizations", f.factorizations},
                      {"residual", f.residual}, {"elastic_energy", f.elastic_energy},
                      {"kinetic_energy", f.kinetic_energy}, {"gravity_energy", f.gravity_energy},
                      {"total_energy", f.total_energy}, {"volume_ratio", f.volume_ratio}, {"min_J", f.min_J},
                      {"inverted", f.inverted}, {"wall_seconds", f.wall_seconds}, {"failure", f.failure}});
  j["frames"] = frames;
  // Non-finite values (an energy undefined at the start) are written as null.
  write_atomically(s.out / "stats.json", [&](std::ostream& o) { o << j.dump(2) << "\n"; });
  write_atomically(s.out / "stats.csv", [&](std::ostream& o) {
    o << "frame,time,substeps,converged,newton_iterations,line_search_steps,linear_iterations,factorizations,residual,"
         "elastic_energy,kinetic_energy,gravity_energy,total_energy,volume_ratio,min_J,inverted,wall_seconds\n";
    for (const FrameStats& f : r.frames)
      o << fmt::format("{},{:.9g},{},{},{},{},{},{},{:.6e},{:.12g},{:.12g},{:.12g},{:.12g},{:.9g},{:.9g},{},{:.6f}\n", f.frame,
                       f.time, f.substeps, f.converged ? 1 : 0, f.newton_iterations, f.line_search_steps,
                       f.linear_iterations, f.factorizations, f.residual, f.elastic_energy, f.kinetic_energy,
                       f.gravity_energy, f.total_energy, f.volume_ratio, f.min_J, f.inverted, f.wall_seconds);
  });
}

}  // namespace

Scene parse_scene(const json& j, const std::filesystem::path& source) {
  const std::string file = source.string();
  Scene s;
  s.source = source;
  Keys top(j, "", file);

  if (const json* mesh = top.get("mesh")) {
    Keys m(*mesh, "mesh", file);
    const json* box = m.get("box");
    const json* mesh_file = m.get("file");
    if ((box != nullptr) == (mesh_file != nullptr)) m.fail("give exactly one of box or file");
    if (mesh_file) {
      if (!mesh_file->is_string() || mesh_file->get<std::string>().empty()) m.fail("expected a file name", "file");
      const std::filesystem::path f = mesh_file->get<std::string>();
      s.mesh_file = f.is_absolute() ? f : source.parent_path() / f;
    } else {
      Keys b(*box, "mesh.box", file);
      s.element = b.choice("element", "hex", {"tet", "hex"}) == "tet" ? CellType::tet4 : CellType::hex8;
      s.resolution = static_cast<int>(b.integer("res", 4, 1, 400));
      s.tet_split = b.choice("tet_split", "paper", {"paper", "mirrored"}) == "mirrored" ? TetSplit::mirrored : TetSplit::paper;
      s.box_min = b.vec3("min").value_or(s.box_min);
      s.box_max = b.vec3("max").value_or(s.box_max);
      if (!(s.box_min.array() < s.box_max.array()).all()) b.fail("min must be below max on every axis");
      b.finish();
    }
    m.finish();
  }

  if (const json* mat = top.get("material")) {
    Keys m(*mat, "material", file);
    if (const json* name = m.get("name")) {
      if (!name->is_string()) m.fail("expected a material name, got " + name->dump(), "name");
      s.material = name->get<std::string>();
    }
    const bool lame = m.has("mu") || m.has("lambda"), youngs = m.has("youngs") || m.has("poisson");
    if (lame && youngs) m.fail("give mu and lambda, or youngs and poisson, not both");
    try {
      if (youngs) {
        if (!m.has("youngs") || !m.has("poisson")) m.fail("youngs and poisson go together");
        s.params = lame_from_youngs(m.number("youngs", 0.0), m.number("poisson", 0.0));
      } else {
        s.params = Lame{m.number("mu", s.params.mu), m.number("lambda", s.params.lambda)};
        validate(s.params);
      }
      s.reparametrize = m.boolean("reparametrize", false);
      (void)make_material(s.material, s.params, s.reparametrize);
    } catch (const SceneError&) {
      throw;
    } catch (const std::exception& e) {
      m.fail(e.what());
    }
    m.finish();
  }
  s.density = top.positive("density", s.density);

  s.integrator = top.choice("integrator", "backward_euler", {"backward_euler", "quasi_static"}) == "quasi_static"
                     ? Integrator::quasi_static
                     : Integrator::backward_euler;
  s.dt = top.positive("dt", s.dt);
  s.end_time = top.positive("end_time", s.end_time);
  s.frames = static_cast<int>(top.integer("frames", s.frames, 1, 100000));
  s.gravity = top.vec3("gravity").value_or(s.gravity);
  if (const json* damping = top.get("damping")) {
    Keys d(*damping, "damping", file);
    s.mass_damping = d.non_negative("mass", 0.0);
    s.stiffness_damping = d.non_negative("stiffness", 0.0);
    d.finish();
  }

  if (const json* pins = top.get("pins")) {
    if (!pins->is_array()) top.fail("expected an array of pin sets", "pins");
    for (std::size_t i = 0; i < pins->size(); ++i) {
      const std::string path = fmt::format("pins[{}]", i);
      Keys p((*pins)[i], path, file);
      PinSet pin;
      pin.select = parse_selection(p, file);
      if (const json* axes = p.get("axes")) {
        if (!axes->is_string() || axes->get<std::string>().empty() ||
            axes->get<std::string>().find_first_not_of("xyz") != std::string::npos)
          p.fail("expected the held coordinates as letters, e.g. \"xyz\" or \"x\", got " + axes->dump(), "axes");
        for (int a = 0; a < 3; ++a) pin.axes[a] = axes->get<std::string>().find(char('x' + a)) != std::string::npos;
      }
      if (const json* motions = p.get("motion")) {
        if (!motions->is_array()) p.fail("expected an array of motions", "motion");
        for (std::size_t k = 0; k < motions->size(); ++k)
          pin.motions.push_back(parse_motion((*motions)[k], fmt::format("{}.motion[{}]", path, k), file, s.end_time));
      }
      p.finish();
      s.pins.push_back(std::move(pin));
    }
  }

  if (const json* initial = top.get("initial")) {
    if (!initial->is_array()) top.fail("expected an array of operations", "initial");
    for (std::size_t i = 0; i < initial->size(); ++i)
      s.initial.push_back(parse_initial((*initial)[i], fmt::format("initial[{}]", i), file));
  }

  // Dynamics resolves small forces (a perturbed, crushed mesh starts with forces near 1e-6): a stricter
  // default than the stretch test's 1e-3.
  s.newton.tolerance = 1e-6;
  if (const json* solver = top.get("solver")) {
    Keys k(*solver, "solver", file);
    s.solver = k.choice("linear", "cholmod", linear_solver_names());
    s.reuse_factor = !k.boolean("refactorize", false);
    s.newton.tolerance = k.positive("tolerance", s.newton.tolerance);
    s.newton.max_iterations = static_cast<int>(k.integer("max_iterations", s.newton.max_iterations, 1, 100000));
    k.finish();
  }

  if (const json* output = top.get("output")) {
    Keys k(*output, "output", file);
    if (const json* dir = k.get("dir")) {
      if (!dir->is_string() || dir->get<std::string>().empty()) k.fail("expected a directory name", "dir");
      s.out = dir->get<std::string>();
    }
    s.write_vtu = k.boolean("vtu", true);
    k.finish();
  }
  if (s.out.empty()) s.out = std::filesystem::path("output") / source.stem();
  top.finish();
  s.settings = j.dump();  // object keys sorted: the same text for the same scene

  // Selections must select something on this mesh.
  const VolumeMesh mesh = scene_mesh(s);
  for (std::size_t i = 0; i < s.pins.size(); ++i)
    (void)select_vertices(s.pins[i].select, mesh.vertices, fmt::format("{}: pins[{}]", file, i));
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

VolumeMesh scene_mesh(const Scene& s, int* reoriented) {
  if (!s.mesh_file.empty()) {
    MeshFile m = read_mesh(s.mesh_file);
    if (reoriented) *reoriented = m.reoriented;
    return std::move(m.mesh);
  }
  VolumeMesh mesh = s.element == CellType::tet4 ? box_tets(s.resolution, s.tet_split) : box_hexes(s.resolution);
  // [−1, 1]³ → [min, max]
  const Eigen::Vector3d half = 0.5 * (s.box_max - s.box_min), mid = 0.5 * (s.box_max + s.box_min);
  mesh.vertices = (half.asDiagonal() * mesh.vertices).colwise() + mid;
  return mesh;
}

Eigen::VectorXd initial_positions(const Scene& s, const VolumeMesh& mesh) {
  Eigen::Matrix3Xd X = mesh.vertices;
  for (std::size_t i = 0; i < s.initial.size(); ++i) {
    const InitialOp& op = s.initial[i];
    const Eigen::Vector3d c = op.center.value_or(centre_of(X));
    switch (op.kind) {
      case InitialOp::Kind::scale: X = (op.vector.asDiagonal() * (X.colwise() - c)).colwise() + c; break;
      case InitialOp::Kind::reflect: X.row(op.axis) = (2.0 * c[op.axis] - X.row(op.axis).array()).matrix(); break;
      case InitialOp::Kind::collapse:
        for (int a = 0; a < 3; ++a) {
          const bool flatten = op.to == InitialOp::To::point || (op.to == InitialOp::To::plane && a == op.axis) ||
                               (op.to == InitialOp::To::line && a != op.axis);
          if (flatten) X.row(a).setConstant(c[a]);
        }
        break;
      case InitialOp::Kind::perturb: {
        std::mt19937_64 rng(op.seed);
        std::uniform_real_distribution<double> u(-op.amplitude, op.amplitude);
        for (Eigen::Index v = 0; v < X.cols(); ++v)
          for (int a = 0; a < 3; ++a) X(a, v) += u(rng);
        break;
      }
      case InitialOp::Kind::move:
        for (int v : select_vertices(op.select, X, fmt::format("{}: initial[{}]", s.source.string(), i))) X.col(v) += op.vector;
        break;
    }
  }
  return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size());
}

SceneResult run_scene(const Scene& s, std::ostream& log, bool live_progress) {
  const auto t_start = Clock::now();
  ensure_writable_directory(s.out);
  int reoriented = 0;
  const VolumeMesh mesh = scene_mesh(s, &reoriented);
  if (!s.mesh_file.empty())
    log << fmt::format("mesh {}: {} vertices, {} {}{}\n", s.mesh_file.string(), mesh.vertex_count(), mesh.cell_count(),
                       mesh.type == CellType::tet4 ? "tets" : "hexes",
                       reoriented ? fmt::format("; warning: {} inverted cell(s) re-oriented", reoriented) : "");
  Eigen::VectorXd x = initial_positions(s, mesh);
  const Eigen::Matrix3Xd X0 = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, mesh.vertex_count());
  // A resume is checked before any work: the checkpoint must exist and match this scene.
  const std::string print = "scene " + (s.settings.empty() ? s.source.string() : s.settings);
  std::optional<Checkpoint> resume_from;
  if (s.resume) resume_from = checkpoint_for_resume(s.out, print, x.size());

  // Pins: each set's vertices and their positions at t = 0 (the base of its motions).
  std::vector<std::uint8_t> fixed(3 * mesh.vertex_count(), 0);
  std::vector<std::vector<int>> pin_vertices;
  std::vector<Eigen::Matrix3Xd> pin_base;
  for (std::size_t i = 0; i < s.pins.size(); ++i) {
    pin_vertices.push_back(select_vertices(s.pins[i].select, mesh.vertices, fmt::format("{}: pins[{}]", s.source.string(), i)));
    Eigen::Matrix3Xd base(3, pin_vertices.back().size());
    for (std::size_t k = 0; k < pin_vertices.back().size(); ++k) {
      const int v = pin_vertices.back()[k];
      base.col(static_cast<Eigen::Index>(k)) = X0.col(v);
      for (int a = 0; a < 3; ++a)
        if (s.pins[i].axes[a]) fixed[3 * v + a] = 1;
    }
    pin_base.push_back(std::move(base));
  }
  auto place_pins = [&](Eigen::VectorXd& state, double t) {
    for (std::size_t i = 0; i < s.pins.size(); ++i) {
      const Eigen::Matrix3Xd P = pin_targets(s.pins[i], pin_base[i], t);
      for (std::size_t k = 0; k < pin_vertices[i].size(); ++k)
        for (int a = 0; a < 3; ++a)
          if (s.pins[i].axes[a]) state[3 * pin_vertices[i][k] + a] = P(a, static_cast<Eigen::Index>(k));
    }
  };

  ElasticTerm elastic(mesh, make_material(s.material, s.params, s.reparametrize));
  const DofMap dofs(fixed);
  const double rest_volume = rest_volumes(elastic.rest()).sum();
  const bool dynamic = s.integrator == Integrator::backward_euler;
  const double frame_dt = s.end_time / s.frames;
  const int substeps = dynamic ? std::max(1, static_cast<int>(std::ceil(frame_dt / s.dt - 1e-9))) : 1;
  const double h = frame_dt / substeps;
  StepTerms terms{.dt = dynamic ? h : 0.0, .gravity = s.gravity, .mass_damping = s.mass_damping,
                  .stiffness_damping = s.stiffness_damping};
  TimeStepTerm potential(elastic, dofs, lumped_mass(elastic, s.density), terms);
  Problem problem(dofs);
  problem.add(elastic);
  problem.add(potential);
  auto solver = make_linear_solver({.name = s.solver, .reuse_factor = s.reuse_factor});

  SceneResult result;
  result.element = mesh.type;
  result.vertices = mesh.vertex_count();
  result.cells = mesh.cell_count();
  log << fmt::format("snh run {}: {} {} ({} vertices), material {}, mu {:g}, lambda {:g}{}, density {:g}\n",
                     s.source.string(), mesh.cell_count(), mesh.type == CellType::tet4 ? "tets" : "hexes",
                     mesh.vertex_count(), s.material, s.params.mu, s.params.lambda,
                     s.reparametrize ? " (linear, reparametrized)" : "", s.density);
  log << fmt::format("{}, {} frames to t = {:g}{}, gravity ({:g}, {:g}, {:g}), solver {}, output {}\n",
                     dynamic ? "backward Euler" : "quasi-static", s.frames, s.end_time,
                     dynamic ? fmt::format(" ({} substeps of {:g} per frame)", substeps, h) : "", s.gravity[0],
                     s.gravity[1], s.gravity[2], s.solver, s.out.string());

  std::vector<bool> pinned(mesh.vertex_count(), false);
  for (const auto& set : pin_vertices)
    for (int v : set) pinned[v] = true;
  FrameWriter frames(s.out, mesh, s.write_vtu, pinned);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.size());
  auto record = [&](FrameStats& f) {
    const ElasticTerm::Deformation d = elastic.deformation(x);
    f.min_J = d.min_J.minCoeff();
    f.inverted = static_cast<int>((d.min_J.array() <= 0.0).count());
    f.volume_ratio = d.volume / rest_volume;
    f.elastic_energy = elastic.energy(x);
    f.kinetic_energy = potential.kinetic_energy(v);
    f.gravity_energy = potential.gravity_energy(x);
    f.total_energy = f.elastic_energy + f.kinetic_energy + f.gravity_energy;
    try {
      frames.write(f.frame, f.time, x, d);
    } catch (const WriteError& e) {
      throw WriteError(fmt::format("frame {}: {} (the frames before it, stats.json and checkpoint.bin are kept)", f.frame,
                                   e.what()));
    }
  };
  auto finish = [&]() {
    if (stop_requested()) {
      result.interrupted_by = stop_signal();
      result.all_converged = false;
      result.failure = fmt::format("interrupted by signal {} after frame {}", result.interrupted_by, result.frames.back().frame);
    }
    result.total_seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
    result.peak_memory_mib = peak_memory_mib();
    result.final_positions = x;
    write_scene_stats(s, result);
    log << fmt::format("{} in {:.3f} s (peak memory {:.0f} MiB); frames, stats.json and stats.csv in {}\n",
                       result.all_converged ? "finished" : "STOPPED: " + result.failure, result.total_seconds,
                       result.peak_memory_mib, s.out.string());
    return result;
  };

  Eigen::VectorXd previous = x;  // quasi-static: the solution one frame back, for extrapolation
  int first = 1;
  if (resume_from) {
    x = resume_from->x;
    (dynamic ? v : previous) = resume_from->aux;
    result.frames = read_frames(s.out, resume_from->step + 1);
    frames.adopt_written(resume_from->step, [&](int i) { return i * frame_dt; });
    first = resume_from->step + 1;
    log << fmt::format("resuming after frame {} (checkpoint in {})\n", resume_from->step, s.out.string());
  } else {
    FrameStats f0;
    const auto t0 = Clock::now();
    record(f0);
    f0.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (!std::isfinite(f0.elastic_energy)) {
      f0.converged = false;
      f0.failure = fmt::format("the initial state is outside the domain of {} ({} element(s) with J <= 0; min J = {:.4g})",
                               s.material, f0.inverted, f0.min_J);
      result.all_converged = false;
      result.failure = f0.failure;
    }
    result.frames.push_back(f0);
    log << fmt::format("frame {:>3}/{}: t = {:.4g}, volume {:.4f}, min J {:.4f}{}\n", 0, s.frames, 0.0, f0.volume_ratio,
                       f0.min_J, f0.failure.empty() ? "" : "  " + f0.failure);
    if (!result.all_converged) return finish();
  }

  for (int frame = first; frame <= s.frames; ++frame) {
    if (stop_requested()) break;
    const auto t_frame = Clock::now();
    const Eigen::VectorXd frame_start_x = x, frame_start_v = v;
    FrameStats f;
    f.frame = frame;
    f.time = frame * frame_dt;
    f.substeps = substeps;
    for (int sub = 1; sub <= substeps; ++sub) {
      const double t = (frame - 1) * frame_dt + sub * h;
      const Eigen::VectorXd x_n = x;
      Eigen::VectorXd guess = dynamic ? Eigen::VectorXd(x + h * v) : (frame > 1 ? Eigen::VectorXd(2.0 * x - previous) : x);
      place_pins(guess, t);
      potential.begin_step(x_n, v);
      if (!std::isfinite(problem.energy(guess))) {  // the prediction leaves the domain: start from x_n
        guess = x_n;
        place_pins(guess, t);
      }
      NewtonOptions newton = s.newton;
      newton.should_stop = [] { return stop_requested(); };
      if (live_progress)
        newton.on_iteration = [&](int it, double r) {
          log << fmt::format("\r\x1b[2Kframe {:>3}/{}: substep {}/{}, Newton iteration {}, |g| = {:.2e} ...", frame,
                             s.frames, sub, substeps, it, r);
          log.flush();
        };
      previous = x_n;
      x = guess;
      const NewtonReport rep = newton_solve(problem, x, *solver, newton);
      if (live_progress) log << "\r\x1b[2K";
      if (rep.interrupted) {  // abandon the frame: back to the last completed substep's state
        x = x_n;
        break;
      }
      f.newton_iterations += rep.iterations;
      f.line_search_steps += rep.line_search_steps;
      f.linear_iterations += rep.linear_iterations;
      f.factorizations += rep.factorizations;
      f.residual = std::max(f.residual, rep.residual);
      if (dynamic) v = (x - x_n) / h;
      if (!rep.converged) {
        f.converged = false;
        f.failure = fmt::format("substep {} (t = {:.6g}): {}{}", sub, t, rep.failure,
                                worst_element(elastic.deformation(x.allFinite() ? x : x_n).min_J));
        if (!x.allFinite()) x = x_n;  // never write a non-finite frame
        break;
      }
    }
    if (stop_requested()) {  // interrupted inside this frame: its substeps are not written
      x = frame_start_x;
      v = frame_start_v;
      break;
    }
    record(f);
    f.wall_seconds = std::chrono::duration<double>(Clock::now() - t_frame).count();
    result.frames.push_back(f);
    log << fmt::format("frame {:>3}/{}: t = {:.4g}, {} Newton iterations, |g| = {:.2e}, energy {:.8g} (kinetic {:.4g}), "
                       "volume {:.4f}, min J {:.4f}, {:.3f} s{}\n",
                       frame, s.frames, f.time, f.newton_iterations, f.residual, f.total_energy, f.kinetic_energy,
                       f.volume_ratio, f.min_J, f.wall_seconds, f.converged ? "" : "  NOT CONVERGED: " + f.failure);
    log.flush();
    if (!f.converged) {
      result.all_converged = false;
      result.failure = fmt::format("frame {}, {}", frame, f.failure);
      break;
    }
    // Everything needed to resume after this frame: the stats so far and the exact state.
    result.total_seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
    write_scene_stats(s, result);
    write_checkpoint(s.out, {.fingerprint = print, .step = frame, .time = f.time, .x = x, .aux = dynamic ? v : previous});
  }
  return finish();
}

}  // namespace snh
