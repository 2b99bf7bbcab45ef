#include "snh/setup/lab.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <sstream>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/material/material.hpp"
#include "snh/material/registry.hpp"
#include "snh/material/stability.hpp"
#include "snh/math/parallel.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/setup/stretch.hpp"

namespace snh {
namespace {

using json = nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<std::string> energies_of(const LabOptions& o) {
  if (!o.energies.empty()) return o.energies;
  std::vector<std::string> all;
  for (auto n : material_names()) all.emplace_back(n);
  return all;
}

/// A cube of hexes (or tets) under backward Euler (substeps of at most 0.05) with mass damping: the lab's
/// common setting. Large steps and strong damping can leave a folded cube stuck for a long time.
Scene cube(const std::string& energy, const Lame& p, int res, double end_time, int frames, double damping,
           CellType element = CellType::hex8) {
  Scene s;
  s.mesh.element = element;
  s.mesh.resolution = res;
  s.material.name = energy;
  s.material.params = p;
  s.time.integrator = Integrator::backward_euler;
  s.time.dt = 0.05;
  s.time.end_time = end_time;
  s.time.frames = frames;
  s.forces.mass_damping = damping;
  s.solver.linear = "ldlt";  // small meshes: a simplicial factorization, no BLAS threads to wake
  // The lab's runs have always used the stretch test's Newton tolerance (1e-3 on |g|, absolute, and no step
  // rule), not a scene file's scale-aware default: kept, so that its tables stay as measured.
  s.solver.tolerance = 1e-3;
  // A step that does not converge is one of the lab's measurements (an energy that cannot take the step),
  // so it is not retried in halves as a scene's would be.
  s.solver.step_halvings = 0;
  s.solver.newton.relative_step_tolerance = 0.0;
  return s;
}

std::mutex progress_mutex;

void report(const LabOptions& o, const std::string& line) {
  if (!o.progress) return;
  const std::lock_guard<std::mutex> lock(progress_mutex);
  *o.progress << line;
  o.progress->flush();
}

/// Runs body(energy, rows) for every energy, the energies spread over the OpenMP threads (each run's own
/// loops then stay on its thread), and concatenates the rows in energy order: the same result for any
/// thread count.
template <class T, class Body>
std::vector<T> per_energy(const LabOptions& o, Body&& body) {
  const std::vector<std::string> energies = energies_of(o);
  std::vector<std::vector<T>> parts(energies.size());
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < static_cast<int>(energies.size()); ++i) errors.run(i, [&] { body(energies[i], parts[i]); });
  errors.rethrow();
  std::vector<T> all;
  for (auto& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

/// Runs one simulation of an experiment into OUT/<experiment>/<case>/<energy> and summarises it.
LabRun simulate(Scene s, const std::string& experiment, const std::string& case_name, const LabOptions& o) {
  LabRun run;  // (member by member: GCC 12 -Wextra warns of designated initializers that leave members to their defaults)
  run.experiment = experiment;
  run.case_name = case_name;
  run.energy = s.material.name;
  s.source = fmt::format("lab {} {} {}", experiment, case_name, s.material.name);
  run.dir = (std::filesystem::path(experiment) / case_name / s.material.name).generic_string();
  s.output.dir = o.out / run.dir;
  std::ostringstream log;
  const SceneResult r = run_scene(s, log);
  run.converged = r.all_converged;
  run.failure = r.failure;
  run.defined_at_start = std::isfinite(r.frames.front().elastic_energy);
  for (const FrameStats& f : r.frames) {
    run.time.push_back(f.time);
    run.volume.push_back(f.volume_ratio);
    if (std::isnan(run.recovery_time) && f.volume_ratio >= 0.99 && f.inverted == 0) run.recovery_time = f.time;
  }
  const FrameStats& last = r.frames.back();
  run.final_volume = last.volume_ratio;
  run.final_min_J = last.min_J;
  run.final_inverted = last.inverted;
  run.final_elastic_energy = last.elastic_energy;
  report(o, fmt::format("lab {:<10} {:<14} {:<22} {}\n", experiment, case_name, s.material.name,
                        !run.defined_at_start ? "undefined at the start"
                        : !run.converged      ? "stopped: " + run.failure
                                              : fmt::format("final volume {:.4f}", run.final_volume)));
  return run;
}

/// One of the lab's tables: printed as text (the first column left-aligned, the others right-aligned to
/// their widths; a width of 0 is free text after two spaces) and stored in lab.json for the report.
struct LabTable {
  std::string title;
  std::vector<std::pair<std::string, int>> columns;  ///< heading, width
  std::vector<std::vector<std::string>> rows;
  [[nodiscard]] std::string text() const {
    auto line = [&](const std::vector<std::string>& cells) {
      std::string out;
      for (std::size_t i = 0; i < cells.size() && i < columns.size(); ++i) {
        const int w = columns[i].second;
        out += i == 0 ? fmt::format("{:<{}}", cells[i], w) : w == 0 ? "  " + cells[i] : fmt::format("{:>{}}", cells[i], w);
      }
      return out + "\n";
    };
    std::vector<std::string> head;
    for (const auto& [name, width] : columns) head.push_back(name);
    std::string out = title + "\n" + line(head);
    for (const auto& r : rows) out += line(r);
    return out;
  }
};

std::string volume_cell(const LabRun& r) {
  if (!r.defined_at_start) return "undefined at start";
  if (!r.converged) return "Newton failed";
  return fmt::format("{:.4f}", r.final_volume);
}

json to_json(const LabRun& r) {
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  return {{"experiment", r.experiment}, {"case", r.case_name}, {"energy", r.energy},
          {"defined_at_start", r.defined_at_start}, {"converged", r.converged}, {"failure", r.failure},
          {"recovered", r.recovered()}, {"final_volume", num(r.final_volume)}, {"final_min_J", num(r.final_min_J)},
          {"final_inverted", r.final_inverted}, {"final_elastic_energy", num(r.final_elastic_energy)},
          {"recovery_time", num(r.recovery_time)}, {"dir", r.dir}, {"time", r.time},
          {"volume", [&] {
             json v = json::array();
             for (double x : r.volume) v.push_back(num(x));
             return v;
           }()}};
}

const LabRun* find(const std::vector<LabRun>& runs, const std::string& case_name, const std::string& energy) {
  for (const LabRun& r : runs)
    if (r.case_name == case_name && r.energy == energy) return &r;
  return nullptr;
}

}  // namespace

bool LabRun::recovered() const {
  return defined_at_start && converged && std::abs(final_volume - 1.0) <= 0.01 && final_inverted == 0;
}

std::vector<LabRun> lab_rest(const LabOptions& o) {
  return per_energy<LabRun>(o, [&](const std::string& e, std::vector<LabRun>& runs) {
    // ν = 0.4 with the parameters used as given (psi_d has no reparametrization): μ = 1, λ = 4.
    const Scene s = cube(e, {1.0, 4.0}, o.quick ? 2 : 3, o.quick ? 8.0 : 12.0, 40, 2.0);
    runs.push_back(simulate(s, "rest", "free_cube", o));
  });
}

std::vector<LabRun> lab_inversion(const LabOptions& o) {
  const Lame p{1.0, 10.0};
  return per_energy<LabRun>(o, [&](const std::string& e, std::vector<LabRun>& runs) {
    Scene reflected = cube(e, p, o.quick ? 2 : 3, o.quick ? 4.0 : 8.0, 40, 0.2);
    reflected.initial.push_back(ReflectOp{});
    runs.push_back(simulate(reflected, "inversion", "reflected", o));
    // Tets; the middle of the top face pushed down through the body by 1.5 (of 2).
    Scene pushed = cube(e, p, o.quick ? 3 : 4, o.quick ? 4.0 : 8.0, 40, 0.2, CellType::tet4);
    MoveOp push;
    push.select.region = Eigen::AlignedBox3d(Eigen::Vector3d(-0.5, 1.0, -0.5), Eigen::Vector3d(0.5, 1.0, 0.5));
    push.by = Eigen::Vector3d(0.0, -1.5, 0.0);
    pushed.initial.push_back(push);
    runs.push_back(simulate(pushed, "inversion", "pushed_through", o));
  });
}

std::vector<LabRun> lab_reflection(const LabOptions& o) {
  return per_energy<LabRun>(o, [&](const std::string& e, std::vector<LabRun>& runs) {
    for (int axis = 0; axis < 3; ++axis) {
      Scene s = cube(e, {1.0, 10.0}, o.quick ? 2 : 3, o.quick ? 4.0 : 8.0, 40, 0.2);
      ReflectOp r;
      r.axis = axis;
      // A small seeded perturbation, the same for every axis, so that no run sits on an exact tie.
      PerturbOp jitter;
      jitter.amplitude = 1e-3;
      s.initial = {r, jitter};
      runs.push_back(simulate(s, "reflection", std::string("reflect_") + char('x' + axis), o));
    }
  });
}

double lab_trap_size() {
  const StabilityReport rep = measure_stability({1.0, 10.0}, false, 1);
  for (const StabilityRow& row : rep.rows)
    if (row.name == "stable_neo_hookean")
      for (const CriticalPoint& c : row.critical_points)
        if (!c.minimum) return c.s;
  return kNaN;
}

std::vector<LabRun> lab_degeneracy(const LabOptions& o) {
  const double trap = lab_trap_size();
  struct Case {
    std::string name;
    InitialOp first;
  };
  std::vector<Case> cases;
  for (auto [name, to] : {std::pair{"plane", CollapseOp::To::plane}, {"line", CollapseOp::To::line}, {"point", CollapseOp::To::point}}) {
    CollapseOp c;
    c.to = to;
    c.axis = 1;
    cases.push_back({name, c});
  }
  for (auto [name, s] : {std::pair{"below_trap", 0.5 * trap}, {"above_trap", 2.0 * trap}}) {
    ScaleOp c;
    c.factors = Eigen::Vector3d::Constant(s);
    cases.push_back({name, c});
  }
  PerturbOp jitter;
  jitter.amplitude = 1e-3;
  return per_energy<LabRun>(o, [&](const std::string& e, std::vector<LabRun>& runs) {
    for (const Case& c : cases) {
      Scene s = cube(e, {1.0, 10.0}, o.quick ? 2 : 3, o.quick ? 4.0 : 8.0, o.quick ? 40 : 80, 0.2);
      s.initial = {c.first, jitter};
      runs.push_back(simulate(s, "degeneracy", c.name, o));
    }
  });
}

std::vector<PoissonRow> lab_poisson(const LabOptions& o) {
  const int res = 2;
  const double strain = 1e-3, length = 4.0;
  return per_energy<PoissonRow>(o, [&](const std::string& e, std::vector<PoissonRow>& rows) {
    for (double nu : {0.3, 0.4, 0.45, 0.49})
      for (bool reparam : {false, true}) {
        PoissonRow row;
        row.energy = e;
        row.nu = row.expected = nu;
        row.reparametrize = reparam;
        Scene s;
        s.mesh.element = CellType::hex8;
        s.mesh.resolution = res;
        s.mesh.min = Eigen::Vector3d::Zero();
        s.mesh.max = Eigen::Vector3d(length, 1.0, 1.0);
        s.material.name = e;
        s.material.params = lame_from_youngs(1.0, nu);
        s.material.reparametrize = reparam;
        s.time.integrator = Integrator::quasi_static;
        s.time.frames = 1;
        s.solver.tolerance = 1e-12;
        s.solver.newton.relative_step_tolerance = 0.0;
        // Sliding ends and symmetry planes: x = 0 holds x, y = 0 holds y, z = 0 holds z, x = L moves in x.
        auto face = [&](int axis, double at) {
          Eigen::Vector3d lo = s.mesh.min, hi = s.mesh.max;
          lo[axis] = hi[axis] = at;
          PinSpec pin;
          pin.select.region = Eigen::AlignedBox3d(lo, hi);
          pin.axes = {axis == 0, axis == 1, axis == 2};
          return pin;
        };
        s.pins = {face(0, 0.0), face(1, 0.0), face(2, 0.0), face(0, length)};
        s.pins.back().motions.push_back(Translate{.by = Eigen::Vector3d(strain * length, 0, 0), .start = 0.0, .end = 1.0});
        s.source = fmt::format("lab poisson {} nu {} {}", e, nu, reparam ? "reparametrized" : "as given");
        const std::string dir = fmt::format("poisson/nu_{}_{}/{}", nu, reparam ? "reparametrized" : "given", e);
        s.output.dir = o.out / dir;
        try {
          const AnyMaterial m = make_material(e, s.material.params, reparam);
          // An energy with stress at rest has no equilibrium at zero strain to measure a ratio against.
          const double rest_stress = std::visit(
              [](const auto& mat) { return evaluate(mat, Mat3::Identity(), PsdProjection::none).P.norm(); }, m);
          if (rest_stress > 1e-9) {
            row.failure = fmt::format("not stress-free at rest (|P(I)| = {:.3g})", rest_stress);
            rows.push_back(row);
            continue;
          }
        } catch (const std::exception& ex) {
          row.failure = ex.what();
          rows.push_back(row);
          continue;
        }
        std::ostringstream log;
        const SceneResult r = run_scene(s, log);
        row.ran = true;
        row.dir = dir;
        if (!r.all_converged) {
          row.failure = r.failure;
        } else {
          const int corner = res + res * (res + 1) + res * (res + 1) * (res + 1);  // lattice (res, res, res)
          const double lateral = r.final_positions[3 * corner + 1] - 1.0;         // y of the corner, rest 1
          row.measured = -lateral / strain;
        }
        report(o, fmt::format("lab poisson    nu {:<5} {:<14} {:<22} measured {:.4f}\n", nu,
                              reparam ? "reparametrized" : "as given", e, row.measured));
        rows.push_back(row);
      }
  });
}

std::vector<StretchRow> lab_stretch(const LabOptions& o) {
  return per_energy<StretchRow>(o, [&](const std::string& e, std::vector<StretchRow>& rows) {
    for (double nu : {0.3, 0.4, 0.45, 0.49, 0.495}) {
      StretchRow row;
      row.energy = e;
      row.nu = nu;
      StretchConfig c;
      c.element = CellType::hex8;
      c.resolution = o.quick ? 5 : 8;
      c.material = e;
      c.params = lame_from_youngs(1.0, nu);
      c.program = "snh lab";
      // Near incompressibility the symmetric state at 3.5x can be a saddle that projected Newton leaves only
      // slowly (docs/results.md, the stretch test): allow more iterations than the paper's 50.
      c.newton.max_iterations = 200;
      c.solver = "ldlt";  // as the scenes: no BLAS threads competing with the parallel runs
      row.dir = fmt::format("stretch/nu_{}/{}", nu, e);
      c.out = o.out / row.dir;
      // Reparametrized where the energy has a reparametrization, so that ν means the same for all.
      try {
        (void)make_material(e, c.params, true);
        c.reparametrize = true;
      } catch (const std::exception&) {
        c.reparametrize = false;
      }
      row.reparametrized = c.reparametrize;
      std::ostringstream log;
      const StretchResult r = run_stretch(c, log);
      row.converged = r.all_converged;
      if (r.all_converged) row.volume_ratio = r.steps.back().volume_ratio;
      else row.failure = r.steps.empty() ? "no step" : r.steps.back().failure;
      report(o, fmt::format("lab stretch    nu {:<5} {:<22} volume {:.4f}\n", nu, e, row.volume_ratio));
      rows.push_back(row);
    }
  });
}

json lab_psi_along_sI(const Lame& p, const std::vector<std::string>& energies) {
  json out;
  std::vector<double> s;
  for (int i = 0; i <= 200; ++i) s.push_back(-0.5 + 0.01 * i);
  out["s"] = s;
  out["mu"] = p.mu;
  out["lambda"] = p.lambda;
  json psi;
  for (const std::string& e : energies) {
    const AnyMaterial m = make_material(e, p, false);
    json values = json::array();
    for (double si : s) {
      const double v = std::visit([&](const auto& mat) { return mat.psi(Eigen::Matrix3d(si * Eigen::Matrix3d::Identity())); }, m);
      values.push_back(std::isfinite(v) ? json(v) : json(nullptr));
    }
    psi[e] = values;
  }
  out["psi"] = psi;
  return out;
}

namespace {

/// Every experiment's results.
struct LabResults {
  std::vector<std::string> energies;
  std::vector<LabRun> rest, inversion, reflection, degeneracy;
  std::vector<PoissonRow> poisson;
  std::vector<StretchRow> stretch;
  double trap = 0.0;
};

/// lab.json's results (before its tables).
json results_json(const LabResults& lab, const LabOptions& o) {
  json j;
  j["quick"] = o.quick;
  j["energies"] = lab.energies;
  j["trap_size"] = lab.trap;
  auto runs_json = [](const std::vector<LabRun>& runs) {
    json a = json::array();
    for (const LabRun& r : runs) a.push_back(to_json(r));
    return a;
  };
  j["rest"] = runs_json(lab.rest);
  j["inversion"] = runs_json(lab.inversion);
  j["reflection"] = runs_json(lab.reflection);
  j["degeneracy"] = runs_json(lab.degeneracy);
  json pj = json::array();
  for (const PoissonRow& r : lab.poisson)
    pj.push_back({{"energy", r.energy}, {"nu", r.nu}, {"reparametrize", r.reparametrize}, {"ran", r.ran},
                  {"expected", r.expected}, {"measured", std::isfinite(r.measured) ? json(r.measured) : json(nullptr)},
                  {"failure", r.failure}, {"dir", r.dir}});
  j["poisson"] = pj;
  json sj = json::array();
  for (const StretchRow& r : lab.stretch)
    sj.push_back({{"energy", r.energy}, {"nu", r.nu}, {"reparametrized", r.reparametrized}, {"converged", r.converged},
                  {"volume_ratio", std::isfinite(r.volume_ratio) ? json(r.volume_ratio) : json(nullptr)},
                  {"failure", r.failure}, {"dir", r.dir}});
  j["stretch"] = sj;
  j["psi_along_sI"] = lab_psi_along_sI({1.0, 10.0}, lab.energies);
  return j;
}

/// The lab's table 1. Rest.
LabTable rest_table(const LabResults& lab) {
  LabTable t;
  t.title = "1. Rest: a free cube starting at rest (mu 1, lambda 4: nu 0.4); volume ratio after settling";
  t.columns = {{"energy", 24}, {"volume", 10}, {"", 0}};
  for (const LabRun& r : lab.rest)
    t.rows.push_back({r.energy, volume_cell(r),
                      !r.converged || !r.defined_at_start ? ""
                      : std::abs(r.final_volume - 1.0) <= 1e-3
                          ? "stays at rest"
                          : fmt::format("drifts (s = {:.3f} per axis)", std::cbrt(r.final_volume))});
  return t;
}

/// The lab's table 2. Inversion.
LabTable inversion_table(const LabResults& lab) {
  LabTable t;
  t.title = "2. Inversion (mu 1, lambda 10): volume ratio at the end; recovered = within 1 % of rest, nothing inverted";
  t.columns = {{"energy", 24}, {"reflected cube", 20}, {"", 12}, {"pushed through", 20}, {"", 12}};
  for (const std::string& e : lab.energies) {
    const LabRun *a = find(lab.inversion, "reflected", e), *b = find(lab.inversion, "pushed_through", e);
    t.rows.push_back({e, volume_cell(*a), a->recovered() ? "recovered" : "no", volume_cell(*b),
                      b->recovered() ? "recovered" : "no"});
  }
  return t;
}

/// The lab's table 3. Reflection.
LabTable reflection_table(const LabResults& lab) {
  LabTable t;
  t.title = "3. Reflection: the inverted cube reflected in x, y or z (same perturbation); final volume ratios";
  t.columns = {{"energy", 24}, {"x", 20}, {"y", 20}, {"z", 20}, {"spread", 16}};
  for (const std::string& e : lab.energies) {
    const LabRun *x = find(lab.reflection, "reflect_x", e), *y = find(lab.reflection, "reflect_y", e),
                 *z = find(lab.reflection, "reflect_z", e);
    std::string spread = "-";
    if (x->converged != y->converged || y->converged != z->converged) spread = "axis-dependent";
    if (x->converged && y->converged && z->converged && x->defined_at_start) {
      const double lo = std::min({x->final_volume, y->final_volume, z->final_volume});
      const double hi = std::max({x->final_volume, y->final_volume, z->final_volume});
      spread = fmt::format("{:.1e}", hi - lo);
    }
    t.rows.push_back({e, volume_cell(*x), volume_cell(*y), volume_cell(*z), spread});
  }
  return t;
}

/// The lab's table 4. Degeneracy.
LabTable degeneracy_table(const LabResults& lab) {
  LabTable t;
  t.title = fmt::format("4. Degeneracy: crushed, then released (perturbation 1e-3); time to 99 % volume, or the volume at "
                        "the end (trap size s = {:.4f}: below = {:.4f}, above = {:.4f})",
                        lab.trap, 0.5 * lab.trap, 2.0 * lab.trap);
  t.columns = {{"energy", 24}, {"plane", 16}, {"line", 16}, {"point", 16}, {"below trap", 16}, {"above trap", 16}};
  for (const std::string& e : lab.energies) {
    std::vector<std::string> row = {e};
    for (const char* c : {"plane", "line", "point", "below_trap", "above_trap"}) {
      const LabRun* r = find(lab.degeneracy, c, e);
      row.push_back(!r->defined_at_start ? "undefined"
                    : !r->converged      ? "Newton failed"
                    : std::isfinite(r->recovery_time) ? fmt::format("{:.2f} s", r->recovery_time)
                                                      : fmt::format("end {:.3f}", r->final_volume));
    }
    t.rows.push_back(row);
  }
  return t;
}

/// The lab's table 5. Poisson's ratio.
LabTable poisson_table(const LabResults& lab) {
  LabTable t;
  t.title = "5. Poisson's ratio: a bar under 0.1 % strain with sliding ends; measured nu (expected = nu, E = 1; "
            "- where the energy has no reparametrization or is not stress-free at rest)";
  t.columns = {{"energy", 24}};
  for (double nu : {0.3, 0.4, 0.45, 0.49}) {
    t.columns.push_back({fmt::format("{} given", nu), 14});
    t.columns.push_back({"reparam.", 14});
  }
  for (const std::string& e : lab.energies) {
    std::vector<std::string> row = {e};
    for (const PoissonRow& r : lab.poisson)
      if (r.energy == e) row.push_back(!r.ran ? "-" : std::isfinite(r.measured) ? fmt::format("{:.4f}", r.measured) : "failed");
    t.rows.push_back(row);
  }
  return t;
}

/// The lab's table 6. Large stretch.
LabTable stretch_test_table(const LabResults& lab) {
  LabTable t;
  t.title = "6. Large stretch: the paper's stretch test (hexes) to 3.5x; volume ratio at the end (E = 1, reparametrized "
            "where the energy has a reparametrization, * where not)";
  t.columns = {{"energy", 24}};
  for (double nu : {0.3, 0.4, 0.45, 0.49, 0.495}) t.columns.push_back({fmt::format("nu {}", nu), 12});
  for (const std::string& e : lab.energies) {
    std::vector<std::string> row = {e};
    for (const StretchRow& r : lab.stretch)
      if (r.energy == e)
        row.push_back(r.converged ? fmt::format("{:.4f}{}", r.volume_ratio, r.reparametrized ? "" : "*") : "failed");
    t.rows.push_back(row);
  }
  return t;
}

}  // namespace

LabReport run_lab(const LabOptions& o) {
  const auto t_start = std::chrono::steady_clock::now();
  ensure_writable_directory(o.out);
  LabResults lab;
  lab.energies = energies_of(o);
  lab.rest = lab_rest(o);
  lab.inversion = lab_inversion(o);
  lab.reflection = lab_reflection(o);
  lab.degeneracy = lab_degeneracy(o);
  lab.poisson = lab_poisson(o);
  lab.stretch = lab_stretch(o);
  lab.trap = lab_trap_size();

  LabReport rep;
  json& j = rep.json;
  j = results_json(lab, o);
  // The tables: one structure, printed as text and stored in lab.json for the report.
  const std::vector<LabTable> tables = {rest_table(lab),       inversion_table(lab), reflection_table(lab),
                                        degeneracy_table(lab), poisson_table(lab),   stretch_test_table(lab)};
  json tj = json::array();
  for (const LabTable& t : tables) {
    rep.text += (rep.text.empty() ? "" : "\n") + t.text();
    json columns = json::array();
    for (const auto& [name, width] : t.columns) columns.push_back(name);
    tj.push_back({{"title", t.title}, {"columns", columns}, {"rows", t.rows}});
  }
  j["tables"] = tj;
  j["command_line"] = o.command_line;
  j["snh_version"] = SNH_VERSION;
  j["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  write_atomically(o.out / "lab.json", [&](std::ostream& out) { out << j.dump(1) << "\n"; });
  return rep;
}

}  // namespace snh
