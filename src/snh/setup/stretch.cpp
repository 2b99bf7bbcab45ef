#include "snh/setup/stretch.hpp"

#include <cmath>
#include <limits>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/material/printable.hpp"

#include "snh/fem/quality.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/io/checksum.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/run/driver.hpp"
#include "snh/sim/simulation.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace snh {

void AxisStretch::targets(double t, Eigen::Matrix3Xd& out) const {
  out = rest_;
  const double l = length(t);
  for (Eigen::Index k = 0; k < out.cols(); ++k) out(axis_, k) = centre_ + (rest_(axis_, k) - centre_) * l;
}

std::string fingerprint(const StretchConfig& c) {
  return fmt::format("stretch: {} material {} mu {:.17g} lambda {:.17g}{}, {} steps to {:.17g}x along {}, tolerance {:.17g}, "
                     "projection {}{}",
                     c.mesh_file.empty() ? fmt::format("{} res {}{}", to_string(c.element), c.resolution,
                                                       c.element == CellType::tet4 && c.tet_split == TetSplit::mirrored
                                                           ? " mirrored"
                                                           : "")
                                         : fmt::format("mesh {} (contents {})", c.mesh_file.string(), file_digest(c.mesh_file)),
                     c.material, c.params.mu, c.params.lambda, c.reparametrize ? " reparametrized" : "", c.steps,
                     c.stretch, char('x' + c.axis), c.newton.tolerance,
                     c.newton.projection == PsdProjection::abs ? "abs" : "clamp",
                     c.newton.try_true_hessian ? "" : ", projected only");
}

void validate(const StretchConfig& c) {
  if (c.axis < 0 || c.axis > 2) throw std::invalid_argument(fmt::format("axis must be 0, 1 or 2, got {}", c.axis));
  if (c.mesh_file.empty() && (c.resolution < 1 || c.resolution > 400))
    throw std::invalid_argument(fmt::format("resolution must be an integer from 1 to 400, got {}", c.resolution));
  if (c.steps < 1 || c.steps > 100000) throw std::invalid_argument(fmt::format("steps must be from 1 to 100000, got {}", c.steps));
  if (!std::isfinite(c.stretch) || c.stretch <= 0.0)
    throw std::invalid_argument(fmt::format("stretch must be a finite number > 0, got {}", c.stretch));
  if (!(c.newton.tolerance > 0.0)) throw std::invalid_argument("tolerance must be > 0");
  if (!is_linear_solver(c.solver))
    throw std::invalid_argument(fmt::format("unknown linear solver '{}'", printable(c.solver)));
  (void)make_material(c.material, c.params, c.reparametrize);  // unknown name or bad parameters
  // The lattice's memory estimate, before building it (a mesh file's is checked by the driver).
  if (c.mesh_file.empty()) {
    // "auto" on the box: the solver it will choose for the free DOFs (all but the two end layers).
    const std::int64_t r = c.resolution;
    const std::string_view solver =
        c.solver == "auto" ? auto_linear_solver(3 * (r + 1) * (r + 1) * std::max<std::int64_t>(r - 1, 0), c.element == CellType::hex8) : c.solver;
    check_memory(lattice_size(c.resolution, c.element), solver, fmt::format("{} res {}", to_string(c.element), c.resolution));
  }
  // The directory itself is made and checked by the run's lock (RunDirectoryLock), which removes it again if
  // the run is refused before writing anything; here only what would stop the lock at once.
  std::error_code ec;
  if (std::filesystem::exists(c.out, ec) && !std::filesystem::is_directory(c.out, ec))
    throw OutputRefused(fmt::format("output directory {} exists and is not a directory", c.out.string()));
}

namespace {

/// The test's mesh (the box, or the mesh file read and checked) and the two extreme layers along the axis
/// (the box's j = 0 and j = res layers), all three coordinates held, moving apart symmetrically about the
/// centre.
struct StretchSetup {
  VolumeMesh mesh;
  int reoriented = 0;
  int axis = 1;
  double centre = 0.0, eps = 0.0;  ///< the layers' centre along the axis; the tolerance of "on a layer"
  SimulationSetup simulation;
};

StretchSetup stretch_setup(const StretchConfig& c) {
  StretchSetup out;
  VolumeMesh& mesh = out.mesh;
  if (c.mesh_file.empty()) {
    mesh = c.element == CellType::tet4 ? box_tets(c.resolution, c.tet_split) : box_hexes(c.resolution);
  } else {
    MeshFile file = read_mesh(c.mesh_file);
    mesh = std::move(file.mesh);
    out.reoriented = file.reoriented;
  }
  const int a = out.axis = c.axis;
  const double lo_a = mesh.vertices.row(a).minCoeff(), hi_a = mesh.vertices.row(a).maxCoeff();
  const double centre = out.centre = 0.5 * (lo_a + hi_a), half0 = 0.5 * (hi_a - lo_a);
  const double eps = out.eps = 1e-9 * std::max(hi_a - lo_a, 1e-300);
  if (!(half0 > 0.0)) throw std::invalid_argument("the mesh is flat along the stretch axis");
  KinematicSet layers;
  layers.name = "the pulled layers";
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.vertices(a, v) <= lo_a + eps) layers.vertices.push_back(static_cast<int>(v));
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.vertices(a, v) >= hi_a - eps) layers.vertices.push_back(static_cast<int>(v));
  const auto stretch = std::make_shared<AxisStretch>(mesh.vertices(Eigen::all, layers.vertices), a, centre, c.stretch, c.steps);
  layers.provider = stretch;

  SimulationSetup& setup = out.simulation;
  setup.mesh = mesh;
  setup.materials = {make_material(c.material, c.params, c.reparametrize)};
  setup.integrator = Integrator::quasi_static;
  setup.kinematic = {layers};
  setup.linear.name = c.solver;
  setup.linear.reuse_factor = c.reuse_factor;
  setup.newton = c.newton;
  // Step 1 starts from the rest state stretched affinely to the new boundary; an extrapolated guess
  // outside the energy's domain falls back to the last solution scaled along the axis to the new boundary
  // (a positive scaling keeps every det F > 0 that was).
  setup.first_guess = [stretch, a, centre](const Eigen::VectorXd& x, double t) {
    Eigen::VectorXd g = x;
    for (Eigen::Index v = 0; v < g.size() / 3; ++v) g[3 * v + a] = centre + (g[3 * v + a] - centre) * stretch->length(t);
    return g;
  };
  setup.fallback_guess = [stretch, a, centre](const Eigen::VectorXd& x, double t) {
    Eigen::VectorXd g = x;
    const double ratio = stretch->length(t) / stretch->length(t - 1.0);
    for (Eigen::Index v = 0; v < g.size() / 3; ++v) g[3 * v + a] = centre + (g[3 * v + a] - centre) * ratio;
    return g;
  };
  return out;
}

/// stats.json's description of the run.
nlohmann::json stretch_settings(const StretchConfig& c, const VolumeMesh& mesh, const Simulation& sim) {
  nlohmann::json settings;
  settings["program"] = c.program;
  if (!c.command_line.empty()) settings["command_line"] = c.command_line;
  settings["element"] = std::string(to_string(mesh.type));
  if (c.mesh_file.empty()) settings["resolution"] = c.resolution;
  else settings["mesh_file"] = c.mesh_file.string();
  settings["material"] = c.material;
  settings["mu"] = c.params.mu;
  settings["lambda"] = c.params.lambda;
  settings["reparametrize"] = c.reparametrize;
  settings["steps_requested"] = c.steps;
  settings["stretch"] = c.stretch;
  settings["solver"] = std::string(sim.solver().name());  // what "auto" chose
  settings["reuse_factor"] = c.reuse_factor;
  settings["axis"] = std::string(1, char('x' + c.axis));
  if (c.element == CellType::tet4) settings["tet_split"] = c.tet_split == TetSplit::paper ? "paper" : "mirrored";
  settings["tolerance"] = c.newton.tolerance;
  settings["vertices"] = mesh.vertex_count();
  settings["cells"] = mesh.cell_count();
  return settings;
}

/// The width of the middle cross-section at x: the layer at the largest rest coordinate along the axis not
/// above the centre (the box's lattice layer j = res/2), measured along the first other axis; NaN where
/// that layer is a single vertex (a width of 0 "of rest 0", as on an unstructured mesh) or the pinned end
/// layer. Sets the result's middle widths; returns the width for stats.json (null where NaN).
nlohmann::json measure_middle(const StretchSetup& st, const Eigen::VectorXd& x, StretchResult& result) {
  const VolumeMesh& mesh = st.mesh;
  const int a = st.axis;
  const double eps = st.eps;
  double layer = -std::numeric_limits<double>::infinity();
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (mesh.vertices(a, v) <= st.centre + eps) layer = std::max(layer, mesh.vertices(a, v));
  const int across = a == 0 ? 1 : 0;
  double lo = 1e300, hi = -1e300, rest_lo = 1e300, rest_hi = -1e300, bottom = 1e300;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    bottom = std::min(bottom, mesh.vertices(a, v));
    if (std::abs(mesh.vertices(a, v) - layer) <= eps) {
      lo = std::min(lo, x[3 * v + across]);
      hi = std::max(hi, x[3 * v + across]);
      rest_lo = std::min(rest_lo, mesh.vertices(across, v));
      rest_hi = std::max(rest_hi, mesh.vertices(across, v));
    }
  }
  const bool meaningful = rest_hi - rest_lo > eps && layer > bottom + eps;
  result.middle_width = meaningful ? hi - lo : std::numeric_limits<double>::quiet_NaN();
  result.middle_rest_width = meaningful ? rest_hi - rest_lo : std::numeric_limits<double>::quiet_NaN();
  return meaningful ? nlohmann::json(result.middle_width) : nlohmann::json(nullptr);
}

/// The driver's plan for the test: its steps, the fingerprint a resume must match, the log's header, lines
/// and summary, and the middle width at the end (into `result`).
RunPlan stretch_plan(const StretchConfig& c, const StretchSetup& st, const Simulation& sim, StretchResult& result) {
  const VolumeMesh& mesh = st.mesh;
  RunPlan plan;
  plan.out = c.out;
  plan.lock = c.lock;
  plan.table = &stretch_table();
  plan.frames = c.steps;
  plan.write_vtu = c.write_vtu;
  plan.progress_interval = c.progress_interval;
  plan.resume = c.resume;
  plan.fingerprint = fingerprint(c);
  plan.settings = stretch_settings(c, mesh, sim);
  plan.live_progress = c.live_progress;
  plan.header = [&c, &st, &sim](std::ostream& o) {
    const VolumeMesh& m = st.mesh;
    o << fmt::format("{}: {}, material {}, mu {:g}, lambda {:g}{}\n", c.program,
                     c.mesh_file.empty() ? fmt::format("resolution {}", c.resolution) : "mesh " + c.mesh_file.string(),
                     c.material, c.params.mu, c.params.lambda, c.reparametrize ? " (linear, reparametrized)" : "");
    if (st.reoriented) o << fmt::format("warning: {} inverted cell(s) of the mesh re-oriented\n", st.reoriented);
    o << fmt::format("{} vertices, {} {}, {} steps to a {:g}x stretch along {}, solver {}, output {}\n", m.vertex_count(),
                     m.cell_count(), m.type == CellType::tet4 ? "tets" : "cubes", c.steps, c.stretch, char('x' + c.axis),
                     c.solver == "auto" ? fmt::format("{} (auto)", sim.solver().name()) : c.solver, c.out.string());
    o << "mesh: " << describe(mesh_quality(sim.elastic().mesh(), sim.elastic().rest()), m.type) << "\n";
  };
  plan.line = [steps = c.steps](const StepRecord& s) {
    return fmt::format("step {:>3}/{}: {} Newton iterations, |f| = {:.2e}, energy {:.8g}, volume {:.4f}, min J {:.4f}, {:.3f} s{}",
                       s.index, steps, s.newton_iterations, s.residual, s.energy, s.volume_ratio, s.min_J, s.wall_seconds,
                       s.converged ? "" : "  NOT CONVERGED: " + s.failure);
  };
  plan.live = [steps = c.steps](int step, int, int it, double r) {
    return fmt::format("step {:>3}/{}: Newton iteration {}, |f| = {:.2e} ...", step, steps, it, r);
  };
  plan.finish = [&st, &sim, &result](const RunResult&, nlohmann::json& stats) { stats["middle_width"] = measure_middle(st, sim.x(), result); };
  plan.summary = [&c, &result](const RunResult& r) {
    std::string out;
    if (r.interrupted_by)
      out = fmt::format("INTERRUPTED by signal {} after step {}: frames 000 to {:03d} and the stats are kept\n",
                        r.interrupted_by, r.records.size(), r.records.size());
    const std::string middle = std::isnan(result.middle_width)
                                   ? std::string("middle cross-section n/a (no vertex layer across the middle)")
                                   : fmt::format("middle cross-section width {:.4f} (rest {:.4g})", result.middle_width,
                                                 result.middle_rest_width);
    return out + fmt::format("{} in {:.3f} s (peak memory {:.0f} MiB); {}; frames ("
                             "NNN.obj{}), stats.json and stats.csv in {}",
                             r.all_converged    ? "converged every step"
                             : r.interrupted_by ? "STOPPED: interrupted"
                                                : "STOPPED: a step did not converge (its last iterate: " + r.failed_frame + ")",
                             r.total_seconds, r.peak_memory_mib, middle, c.write_vtu ? ", NNN.vtu, frames.pvd" : "",
                             c.out.string());
  };
  return plan;
}

}  // namespace

StretchResult run_stretch(const StretchConfig& c, std::ostream& log) {
  validate(c);
  StretchSetup st = stretch_setup(c);
  Simulation sim(std::move(st.simulation));
  StretchResult result;
  result.element = st.mesh.type;
  result.vertices = st.mesh.vertex_count();
  result.cells = st.mesh.cell_count();
  const RunPlan plan = stretch_plan(c, st, sim, result);
  RunResult run = run_simulation(sim, plan, log);
  static_cast<RunOutcome&>(result) = run;
  result.steps = std::move(run.records);
  return result;
}

}  // namespace snh
