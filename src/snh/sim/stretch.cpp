#include "snh/sim/stretch.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/fem/quality.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/sim/checkpoint.hpp"
#include "snh/sim/interrupt.hpp"
#include "snh/sim/output.hpp"

namespace snh {
namespace {

using Clock = std::chrono::steady_clock;

/// Length at step s relative to the rest length.
double half_length(const StretchConfig& c, int s) { return 1.0 + (c.stretch - 1.0) * s / c.steps; }

/// Min det F, inverted-element count and volume ratio of a deformation.
void record_deformation(const ElasticTerm::Deformation& d, double rest_volume, StepStats& st) {
  st.min_J = d.min_J.minCoeff();
  st.inverted = static_cast<int>((d.min_J.array() <= 0.0).count());
  st.volume_ratio = d.volume / rest_volume;
}

/// The per-step stats of the first `count` steps of DIR/stats.json (a resumed run's history).
std::vector<StepStats> read_steps(const std::filesystem::path& dir, int count) {
  std::vector<StepStats> out;
  for (const auto& s : history_for_resume(dir, "steps", count)) {
    StepStats st;
    st.step = s.value("step", 0);
    st.converged = s.value("converged", false);
    st.newton_iterations = s.value("newton_iterations", 0);
    st.line_search_steps = s.value("line_search_steps", 0);
    st.linear_iterations = s.value("linear_iterations", 0);
    st.factorizations = s.value("factorizations", 0);
    st.true_hessian_steps = s.value("true_hessian_steps", 0);
    st.residual = s.value("residual", 0.0);
    st.energy = s.value("energy", 0.0);
    st.wall_seconds = s.value("wall_seconds", 0.0);
    st.assembly_seconds = s.value("assembly_seconds", 0.0);
    st.solve_seconds = s.value("solve_seconds", 0.0);
    st.min_J = s.value("min_J", 0.0);
    st.inverted = s.value("inverted", 0);
    st.volume_ratio = s.value("volume_ratio", 1.0);
    st.residuals = s.value("residual_history", std::vector<double>{});
    st.failure = s.value("failure", std::string());
    out.push_back(st);
  }
  return out;
}

void write_stats(const StretchConfig& c, const StretchResult& r) {
  nlohmann::json j;
  j["program"] = c.program;
  if (!c.command_line.empty()) j["command_line"] = c.command_line;
  j["snh_version"] = SNH_VERSION;
  j["element"] = std::string(to_string(r.element));
  if (c.mesh_file.empty()) j["resolution"] = c.resolution;
  j["material"] = c.material;
  j["mu"] = c.params.mu;
  j["lambda"] = c.params.lambda;
  j["reparametrize"] = c.reparametrize;
  j["steps_requested"] = c.steps;
  j["stretch"] = c.stretch;
  j["solver"] = c.solver;
  j["reuse_factor"] = c.reuse_factor;
  if (!c.mesh_file.empty()) j["mesh_file"] = c.mesh_file.string();
  j["axis"] = std::string(1, char('x' + c.axis));
  if (c.element == CellType::tet4) j["tet_split"] = c.tet_split == TetSplit::paper ? "paper" : "mirrored";
  j["tolerance"] = c.newton.tolerance;
  j["vertices"] = r.vertices;
  j["cells"] = r.cells;
  j["all_converged"] = r.all_converged;
  j["interrupted_by_signal"] = r.interrupted_by;
  j["total_seconds"] = r.total_seconds;
  j["middle_width"] = r.middle_width;
  j["peak_memory_mib"] = r.peak_memory_mib;
  int newton = 0, linear = 0, factorizations = 0, true_steps = 0;
  double assembly = 0, solve = 0;
  for (const auto& s : r.steps) {
    newton += s.newton_iterations;
    linear += s.linear_iterations;
    factorizations += s.factorizations;
    true_steps += s.true_hessian_steps;
    assembly += s.assembly_seconds;
    solve += s.solve_seconds;
  }
  j["newton_iterations"] = newton;
  j["linear_iterations"] = linear;
  j["factorizations"] = factorizations;
  j["true_hessian_steps"] = true_steps;
  j["assembly_seconds"] = assembly;
  j["solve_seconds"] = solve;
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& s : r.steps)
    steps.push_back({{"step", s.step}, {"converged", s.converged}, {"newton_iterations", s.newton_iterations},
                     {"line_search_steps", s.line_search_steps}, {"linear_iterations", s.linear_iterations},
                     {"factorizations", s.factorizations},
                     {"true_hessian_steps", s.true_hessian_steps}, {"residual", s.residual}, {"energy", s.energy}, {"wall_seconds", s.wall_seconds},
                     {"assembly_seconds", s.assembly_seconds}, {"solve_seconds", s.solve_seconds},
                     {"min_J", s.min_J}, {"inverted", s.inverted}, {"volume_ratio", s.volume_ratio},
                     {"residual_history", s.residuals}, {"failure", s.failure}});
  j["steps"] = steps;
  write_atomically(c.out / "stats.json", [&](std::ostream& o) { o << j.dump(2) << "\n"; });
  write_atomically(c.out / "stats.csv", [&](std::ostream& o) {
    o << "step,converged,newton_iterations,line_search_steps,linear_iterations,factorizations,residual,energy,"
         "wall_seconds,assembly_seconds,solve_seconds,min_J,inverted,volume_ratio\n";
    for (const auto& s : r.steps)
      o << fmt::format("{},{},{},{},{},{},{:.6e},{:.12g},{:.6f},{:.6f},{:.6f},{:.9g},{},{:.9g}\n", s.step, s.converged ? 1 : 0,
                       s.newton_iterations, s.line_search_steps, s.linear_iterations, s.factorizations, s.residual, s.energy,
                       s.wall_seconds, s.assembly_seconds, s.solve_seconds, s.min_J, s.inverted, s.volume_ratio);
  });
}

}  // namespace

std::string fingerprint(const StretchConfig& c) {
  return fmt::format("stretch: {} material {} mu {:.17g} lambda {:.17g}{}, {} steps to {:.17g}x along {}, tolerance {:.17g}, "
                     "projection {}{}",
                     c.mesh_file.empty() ? fmt::format("{} res {}{}", to_string(c.element), c.resolution,
                                                       c.element == CellType::tet4 && c.tet_split == TetSplit::mirrored
                                                           ? " mirrored"
                                                           : "")
                                         : "mesh " + c.mesh_file.string(),
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
  (void)make_material(c.material, c.params, c.reparametrize);  // unknown name or bad parameters
  ensure_writable_directory(c.out);
}

StretchResult run_stretch(const StretchConfig& c, std::ostream& log) {
  validate(c);
  const auto t_start = Clock::now();
  const int res = c.resolution;
  int reoriented = 0;
  VolumeMesh mesh;
  if (c.mesh_file.empty()) {
    mesh = c.element == CellType::tet4 ? box_tets(res, c.tet_split) : box_hexes(res);
  } else {
    MeshFile file = read_mesh(c.mesh_file);
    mesh = std::move(file.mesh);
    reoriented = file.reoriented;
  }

  // A resume is checked before any work: the checkpoint must exist and match these settings.
  const std::string print = fingerprint(c);
  std::optional<Checkpoint> resume_from;
  if (c.resume) resume_from = checkpoint_for_resume(c.out, print, 3 * mesh.vertex_count());

  // Kinematic vertices: the two extreme layers along the axis (the box's j = 0 and j = res layers),
  // all three coordinates; they move apart symmetrically about the centre.
  const int a = c.axis;
  const double lo_a = mesh.vertices.row(a).minCoeff(), hi_a = mesh.vertices.row(a).maxCoeff();
  const double centre = 0.5 * (lo_a + hi_a), half0 = 0.5 * (hi_a - lo_a), eps = 1e-9 * std::max(hi_a - lo_a, 1e-300);
  if (!(half0 > 0.0)) throw std::invalid_argument("the mesh is flat along the stretch axis");
  std::vector<std::uint8_t> fixed(3 * mesh.vertex_count(), 0);
  std::vector<int> bottom, top;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    if (mesh.vertices(a, v) <= lo_a + eps) bottom.push_back(static_cast<int>(v));
    if (mesh.vertices(a, v) >= hi_a - eps) top.push_back(static_cast<int>(v));
  }
  for (int v : bottom) fixed[3 * v] = fixed[3 * v + 1] = fixed[3 * v + 2] = 1;
  for (int v : top) fixed[3 * v] = fixed[3 * v + 1] = fixed[3 * v + 2] = 1;
  auto along = [&](double rest_coordinate, int s) { return centre + (rest_coordinate - centre) * half_length(c, s); };

  StretchResult result;
  result.element = mesh.type;
  result.vertices = mesh.vertex_count();
  result.cells = mesh.cell_count();
  ElasticTerm elastic(mesh, make_material(c.material, c.params, c.reparametrize));
  Problem problem{DofMap(fixed)};
  problem.add(elastic);
  auto solver = make_linear_solver({.name = c.solver, .reuse_factor = c.reuse_factor});

  log << fmt::format("{}: {}, material {}, mu {:g}, lambda {:g}{}\n", c.program,
                     c.mesh_file.empty() ? fmt::format("resolution {}", res) : "mesh " + c.mesh_file.string(), c.material,
                     c.params.mu, c.params.lambda, c.reparametrize ? " (linear, reparametrized)" : "");
  if (reoriented) log << fmt::format("warning: {} inverted cell(s) of the mesh re-oriented\n", reoriented);
  log << fmt::format("{} vertices, {} {}, {} steps to a {:g}x stretch along {}, solver {}, output {}\n",
                     mesh.vertex_count(), mesh.cell_count(), mesh.type == CellType::tet4 ? "tets" : "cubes", c.steps,
                     c.stretch, char('x' + a), c.solver, c.out.string());
  log << "mesh: " << describe(mesh_quality(elastic.mesh(), elastic.rest()), mesh.type) << "\n";

  Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size());
  std::vector<bool> pinned(mesh.vertex_count(), false);
  for (const auto* layer : {&bottom, &top})
    for (int v : *layer) pinned[v] = true;
  FrameWriter frames(c.out, mesh, c.write_vtu, pinned);
  const double rest_volume = rest_volumes(elastic.rest()).sum();
  Eigen::VectorXd previous = x;  // the solution one step back, for extrapolation
  int first = 1;
  if (resume_from) {
    const Checkpoint& ck = *resume_from;
    x = ck.x;
    previous = ck.aux;
    result.steps = read_steps(c.out, ck.step);
    frames.adopt_written(ck.step, [](int i) { return static_cast<double>(i); });
    first = ck.step + 1;
    log << fmt::format("resuming after step {} (checkpoint in {})\n", ck.step, c.out.string());
  } else {
    frames.write(0, 0.0, x, elastic.deformation(x));
  }

  for (int s = first; s <= c.steps; ++s) {
    if (stop_requested()) {
      result.interrupted_by = stop_signal();
      break;
    }
    const auto t_step = Clock::now();
    // Initial guess: linear extrapolation from the last two solutions; at step 1, the rest state
    // stretched affinely to the new boundary.
    Eigen::VectorXd guess;
    if (s == 1) {
      guess = x;
      for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) guess[3 * v + a] = along(guess[3 * v + a], 1);
    } else {
      guess = 2.0 * x - previous;
    }
    for (const auto* layer : {&bottom, &top})
      for (int v : *layer) {
        guess.segment<3>(3 * v) = mesh.vertices.col(v);
        guess[3 * v + a] = along(mesh.vertices(a, v), s);
      }
    // An extrapolated guess outside the energy's domain falls back to the last solution scaled along y
    // to the new boundary (a positive scaling keeps every det F > 0 that was).
    if (!std::isfinite(problem.energy(guess))) {
      guess = x;
      const double ratio = half_length(c, s) / half_length(c, s - 1);
      for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) guess[3 * v + a] = centre + (guess[3 * v + a] - centre) * ratio;
    }
    previous = x;
    x = guess;
    NewtonOptions newton = c.newton;
    newton.should_stop = [] { return stop_requested(); };
    if (c.live_progress)
      newton.on_iteration = [&](int it, double r) {
        log << fmt::format("\r\x1b[2Kstep {:>3}/{}: Newton iteration {}, |f| = {:.2e} ...", s, c.steps, it, r);
        log.flush();
      };
    const NewtonReport rep = newton_solve(problem, x, *solver, newton);
    if (c.live_progress) log << "\r\x1b[2K";
    if (rep.interrupted) {  // abandon this step: the state stays at the last completed one
      x = previous;
      result.interrupted_by = stop_signal();
      break;
    }

    StepStats st;
    st.step = s;
    st.converged = rep.converged;
    st.newton_iterations = rep.iterations;
    st.line_search_steps = rep.line_search_steps;
    st.linear_iterations = rep.linear_iterations;
    st.factorizations = rep.factorizations;
    st.true_hessian_steps = rep.true_hessian_steps;
    st.residual = rep.residual;
    st.energy = rep.energy;
    st.assembly_seconds = rep.assembly_seconds;
    st.solve_seconds = rep.solve_seconds;
    st.residuals = rep.residuals;
    const ElasticTerm::Deformation deformed = elastic.deformation(x);
    if (!rep.converged) st.failure = rep.failure + worst_element(deformed.min_J);
    record_deformation(deformed, rest_volume, st);
    try {
      frames.write(s, s, x, deformed);
    } catch (const WriteError& e) {
      throw WriteError(fmt::format("step {}: {} (frames 000 to {:03d}, stats.json and checkpoint.bin are kept: --resume "
                                   "continues once the output can be written)",
                                   s, e.what(), s - 1));
    }
    st.wall_seconds = std::chrono::duration<double>(Clock::now() - t_step).count();
    result.steps.push_back(st);
    log << fmt::format("step {:>3}/{}: {} Newton iterations, |f| = {:.2e}, energy {:.8g}, volume {:.4f}, min J {:.4f}, {:.3f} s{}\n",
                       s, c.steps, st.newton_iterations, st.residual, st.energy, st.volume_ratio, st.min_J,
                       st.wall_seconds, st.converged ? "" : "  NOT CONVERGED: " + st.failure);
    log.flush();
    if (!st.converged) {
      result.all_converged = false;
      break;
    }
    // Everything needed to resume after this step: the stats so far and the exact state.
    result.total_seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
    write_stats(c, result);
    write_checkpoint(c.out, {.fingerprint = print, .step = s, .time = static_cast<double>(s), .x = x, .aux = previous});
  }

  // Middle cross-section: the layer at the largest rest coordinate along the axis not above the centre
  // (the box's lattice layer j = res/2), measured along the first other axis.
  {
    double layer = -std::numeric_limits<double>::infinity();
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
      if (mesh.vertices(a, v) <= centre + eps) layer = std::max(layer, mesh.vertices(a, v));
    const int across = a == 0 ? 1 : 0;
    double lo = 1e300, hi = -1e300, rest_lo = 1e300, rest_hi = -1e300;
    for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
      if (std::abs(mesh.vertices(a, v) - layer) <= eps) {
        lo = std::min(lo, x[3 * v + across]);
        hi = std::max(hi, x[3 * v + across]);
        rest_lo = std::min(rest_lo, mesh.vertices(across, v));
        rest_hi = std::max(rest_hi, mesh.vertices(across, v));
      }
    result.middle_width = hi - lo;
    result.middle_rest_width = rest_hi - rest_lo;
  }
  result.total_seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
  result.peak_memory_mib = peak_memory_mib();
  if (result.interrupted_by) result.all_converged = false;
  write_stats(c, result);
  if (result.interrupted_by)
    log << fmt::format("INTERRUPTED by signal {} after step {}: frames 000 to {:03d} and the stats are kept\n",
                       result.interrupted_by, result.steps.size(), result.steps.size());
  log << fmt::format("{} in {:.3f} s (peak memory {:.0f} MiB); middle cross-section width {:.4f} (rest {:.4g}); frames ("
                     "NNN.obj{}), stats.json and stats.csv in {}\n",
                     result.all_converged    ? "converged every step"
                     : result.interrupted_by ? "STOPPED: interrupted"
                                             : "STOPPED: a step did not converge",
                     result.total_seconds, result.peak_memory_mib, result.middle_width, result.middle_rest_width,
                     c.write_vtu ? ", NNN.vtu, frames.pvd" : "", c.out.string());
  return result;
}

}  // namespace snh
