// snh.Simulation (a stepping simulation whose pinned vertices follow targets set from Python, with the
// elastic energy, gradient and Hessian at any positions) and snh.run_scene (a scene file or dict, run into
// its directory as snh run does).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cmath>
#include <future>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include <fmt/format.h>
#include <omp.h>
#include <pybind11/functional.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "common.hpp"
#include "snh/fem/hessian_layout.hpp"
#include "snh/io/mesh_check.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/run/run_directory.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/sim/simulation.hpp"
#ifdef SNH_PYTHON_REPORT
#include "snh/report/report.hpp"
#endif

namespace snh::py {
namespace {

/// The pinned vertices' targets, as Python last set them for the end t1 of a step: between the step's start t0
/// and t1 (a stage of TR-BDF2, a step split or halved) the pins move on the straight line from where the step
/// found them, so that they reach the targets at t1 and not before; at and after t1, and for a step that
/// does not go forward in time (quasi-static runs may set any t), the targets themselves.
class PythonTargets final : public KinematicProvider {
 public:
  explicit PythonTargets(Eigen::Matrix3Xd initial) : targets_(std::move(initial)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    if (t0_ < t && t < t1_ && start_.cols() == targets_.cols()) out = start_ + ((t - t0_) / (t1_ - t0_)) * (targets_ - start_);
    else out = targets_;
  }
  /// A step from t0, the pins at `start`, to t1.
  void begin(double t0, Eigen::Matrix3Xd start, double t1) {
    t0_ = t0;
    t1_ = t1;
    start_ = std::move(start);
  }
  Eigen::Matrix3Xd targets_;

 private:
  Eigen::Matrix3Xd start_;
  double t0_ = 0.0, t1_ = 0.0;
};

void require(bool ok, const std::string& message) {
  if (!ok) value_error(message);
}

/// A finite number ≥ lo (> lo when strict), or ValueError naming it.
double checked(double v, const char* name, double lo, bool strict) {
  require(std::isfinite(v) && (strict ? v > lo : v >= lo),
          fmt::format("{} must be a finite number {} {:g}, got {}", name, strict ? ">" : ">=", lo, v));
  return v;
}

std::vector<int> vertex_indices(const pyb::handle& obj, Eigen::Index vertices) {
  std::vector<int> out;
  if (obj.is_none()) return out;
  pyb::array a = pyb::array::ensure(obj);
  require(a && (a.dtype().kind() == 'i' || a.dtype().kind() == 'u'),
          "pinned must be an array of integer vertex indices");
  require(a.ndim() == 1, fmt::format("pinned must have shape (k,), got {}", shape_text(a)));
  const auto idx = pyb::array_t<std::int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(a);
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(vertices), 0);
  for (pyb::ssize_t k = 0; k < idx.size(); ++k) {
    const std::int64_t v = idx.data()[k];
    require(v >= 0 && v < vertices, fmt::format("pinned[{}] = {} is not a vertex index (0 to {})", k, v, vertices - 1));
    require(!seen[static_cast<std::size_t>(v)], fmt::format("pinned[{}] = {}: vertex {} is pinned twice", k, v, v));
    seen[static_cast<std::size_t>(v)] = 1;
    out.push_back(static_cast<int>(v));
  }
  return out;
}

class PySimulation {
 public:
  PySimulation(const pyb::handle& vertices, const pyb::handle& cells, const pyb::handle& material, const pyb::handle& pinned,
               const std::string& integrator, double dt, double density, const pyb::handle& gravity, double mass_damping,
               double stiffness_damping, const pyb::handle& initial, const pyb::handle& initial_velocity,
               const std::string& solver, bool reuse_factor,
               double tolerance, double step_tolerance, double relative_step_tolerance, int max_iterations,
               int step_halvings, const std::string& projection_name, const pyb::object& first_guess) {
    MeshFile file;
    file.mesh = mesh_of(vertices, cells);
    check_mesh(file, "mesh");
    reoriented_ = file.reoriented;
    const Eigen::Index n = file.mesh.vertex_count();

    SimulationSetup setup;
    const std::optional<Integrator> chosen = integrator_named(integrator);
    require(chosen.has_value(), fmt::format("integrator must be quasi_static, backward_euler, bdf2 or tr_bdf2, got '{}'", integrator));
    setup.integrator = *chosen;
    setup.dt = checked(dt, "dt", 0.0, true);
    setup.density = checked(density, "density", 0.0, true);
    const Doubles g = real_array(gravity, "gravity", {3});
    setup.gravity = Eigen::Vector3d(g.data()[0], g.data()[1], g.data()[2]);
    setup.mass_damping = checked(mass_damping, "mass_damping", 0.0, false);
    setup.stiffness_damping = checked(stiffness_damping, "stiffness_damping", 0.0, false);
    if (!initial.is_none()) setup.initial = positions_vector(initial, "initial", n);
    if (!initial_velocity.is_none()) {
      require(is_dynamic(setup.integrator), "initial_velocity needs a dynamic integrator (backward_euler, bdf2 or tr_bdf2)");
      setup.initial_velocity = positions_vector(initial_velocity, "initial_velocity", n);
    }
    setup.linear.name = solver;
    setup.linear.reuse_factor = reuse_factor;
    setup.newton.tolerance = checked(tolerance, "tolerance", 0.0, false);
    setup.newton.step_tolerance = checked(step_tolerance, "step_tolerance", 0.0, false);
    setup.newton.relative_step_tolerance = checked(relative_step_tolerance, "relative_step_tolerance", 0.0, false);
    require(max_iterations >= 1 && max_iterations <= 100000,
            fmt::format("max_iterations must be from 1 to 100000, got {}", max_iterations));
    setup.newton.max_iterations = max_iterations;
    require(step_halvings >= 0 && step_halvings <= 20, fmt::format("step_halvings must be from 0 to 20, got {}", step_halvings));
    setup.step_halvings = step_halvings;
    setup.newton.projection = projection(projection_name);
    setup.materials = {any_material(material)};

    pinned_ = vertex_indices(pinned, n);
    if (!pinned_.empty()) {
      const Eigen::VectorXd start =
          setup.initial.size() ? setup.initial : Eigen::Map<const Eigen::VectorXd>(file.mesh.vertices.data(), 3 * n);
      Eigen::Matrix3Xd at(3, static_cast<Eigen::Index>(pinned_.size()));
      for (std::size_t k = 0; k < pinned_.size(); ++k) at.col(static_cast<Eigen::Index>(k)) = start.segment<3>(3 * pinned_[k]);
      targets_ = std::make_shared<PythonTargets>(at);
      KinematicSet set;
      set.name = "pinned";
      set.vertices = pinned_;
      set.provider = targets_;
      setup.kinematic = {set};
    }
    if (!first_guess.is_none()) {
      require(PyCallable_Check(first_guess.ptr()), "first_guess must be a function (x, t) -> positions (n, 3)");
      setup.first_guess = [first_guess, n](const Eigen::VectorXd& x, double t) {
        return positions_vector(first_guess(positions_array(x), t), "first_guess's result", n);
      };
    }
    setup.mesh = std::move(file.mesh);
    sim_ = std::make_unique<Simulation>(std::move(setup));
  }

  [[nodiscard]] Eigen::Index vertices() const { return sim_->mesh().vertex_count(); }

  void set_targets(const pyb::handle& obj) {
    const auto k = static_cast<Eigen::Index>(pinned_.size());
    require(k > 0, "set_targets: this simulation has no pinned vertices");
    const Doubles a = real_array(obj, "targets", {k, 3});
    targets_->targets_ = Eigen::Map<const Eigen::Matrix3Xd>(a.data(), 3, k);
  }

  [[nodiscard]] Doubles targets() const {
    const Eigen::Matrix3Xd& t = targets_ ? targets_->targets_ : Eigen::Matrix3Xd(3, 0);
    Doubles a = new_array({t.cols(), 3});
    std::copy(t.data(), t.data() + t.size(), a.mutable_data());
    return a;
  }

  pyb::dict step(std::optional<double> t_opt, bool check) {
    const double t = t_opt ? *t_opt : sim_->time() + (sim_->dynamic() ? sim_->setup().dt : 1.0);
    require(std::isfinite(t), fmt::format("t must be a finite number, got {}", t));
    // A dynamic step goes forward by t − time: a time at or before the current one would advance the physics
    // by dt while setting the clock back. (Quasi-statically t only sets the pins' targets: any t goes.)
    require(!sim_->dynamic() || t > sim_->time(),
            fmt::format("t must be after the current time {:g} for {}, got {:g}", sim_->time(),
                        integrator_name(sim_->setup().integrator), t));
    // Ctrl-C: Python's handler only records the signal; Newton asks between iterations.
    NewtonOptions options = sim_->setup().newton;
    options.should_stop = [] { return PyErr_CheckSignals() != 0; };
    if (targets_) {
      Eigen::Matrix3Xd start(3, static_cast<Eigen::Index>(pinned_.size()));
      for (std::size_t k = 0; k < pinned_.size(); ++k) start.col(static_cast<Eigen::Index>(k)) = sim_->x().segment<3>(3 * pinned_[k]);
      targets_->begin(sim_->time(), std::move(start), t);
    }
    const StepReport r = sim_->step(t, &options);
    if (r.interrupted) throw pyb::error_already_set();
    if (!r.converged && check) throw std::runtime_error(fmt::format("step to t = {:g}: {}", t, r.failure));
    const ElasticTerm::Deformation d = sim_->elastic().deformation(sim_->x());
    pyb::dict s;
    s["time"] = t;
    s["converged"] = r.converged;
    s["failure"] = r.failure;
    s["halvings"] = r.halvings;
    s["iterations"] = r.newton.iterations;
    s["line_search_steps"] = r.newton.line_search_steps;
    s["linear_iterations"] = r.newton.linear_iterations;
    s["factorizations"] = r.newton.factorizations;
    s["true_hessian_steps"] = r.newton.true_hessian_steps;
    s["truncated_steps"] = r.newton.truncated_steps;
    s["chord_steps"] = r.newton.chord_steps;
    s["residual"] = r.newton.residual;
    s["residuals"] = r.newton.residuals;
    s["energy"] = r.newton.energy;
    s["elastic_energy"] = sim_->elastic().energy(sim_->x());
    s["min_J"] = d.min_J.size() ? d.min_J.minCoeff() : 1.0;
    s["volume_ratio"] = d.volume / sim_->rest_volume();
    s["assembly_seconds"] = r.newton.assembly_seconds;
    s["solve_seconds"] = r.newton.solve_seconds;
    return s;
  }

  [[nodiscard]] Eigen::VectorXd state_or(const pyb::handle& x) const {
    return x.is_none() ? sim_->x() : positions_vector(x, "x", vertices());
  }

  [[nodiscard]] double energy(const pyb::handle& x) const { return sim_->elastic().energy(state_or(x)); }

  [[nodiscard]] Doubles gradient(const pyb::handle& x) const {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3 * vertices());
    const double e = sim_->elastic().evaluate(state_or(x), &g, nullptr, PsdProjection::none);
    require(std::isfinite(e), "gradient: the energy is undefined at x (an element with J <= 0)");
    return positions_array(g);
  }

  /// The elastic Hessian over every DOF (3 #V, DOF 3 v + k), symmetric, as CSR arrays.
  [[nodiscard]] pyb::object hessian(const pyb::handle& x_obj, const std::string& proj) {
    const PsdProjection p = projection(proj);
    const Eigen::VectorXd x = state_or(x_obj);
    const ElasticTerm& elastic = sim_->elastic();
    require(std::isfinite(elastic.energy(x)), "hessian: the energy is undefined at x (an element with J <= 0)");
    const int n = static_cast<int>(x.size());
    if (!layout_) {
      std::vector<int> numbering(static_cast<std::size_t>(n));
      for (int d = 0; d < n; ++d) numbering[static_cast<std::size_t>(d)] = d;
      Stencil cells;
      elastic.stencil(x, cells);
      layout_ = std::make_unique<HessianLayout>(std::move(numbering), n, std::vector<const Stencil*>{&cells});
      scatter_ = elastic.scatter_map(*layout_);
    }
    SparseLower lower = layout_->pattern();
    std::fill(lower.valuePtr(), lower.valuePtr() + lower.nonZeros(), 0.0);
    elastic.add_hessian(x, scatter_, lower.valuePtr(), p);
    Eigen::SparseMatrix<double, Eigen::RowMajor, int> full = lower.selfadjointView<Eigen::Lower>();
    full.makeCompressed();
    auto copy = [](const auto* p, Eigen::Index count, auto tag) {
      pyb::array_t<decltype(tag)> a(count);
      std::copy(p, p + count, a.mutable_data());
      return a;
    };
    auto indptr = copy(full.outerIndexPtr(), full.rows() + 1, std::int32_t{});
    auto indices = copy(full.innerIndexPtr(), full.nonZeros(), std::int32_t{});
    auto data = copy(full.valuePtr(), full.nonZeros(), double{});
    try {
      pyb::module_ sparse = pyb::module_::import("scipy.sparse");
      return sparse.attr("csr_matrix")(pyb::make_tuple(data, indices, indptr), pyb::arg("shape") = pyb::make_tuple(n, n));
    } catch (const pyb::error_already_set& e) {
      if (!e.matches(PyExc_ImportError)) throw;
      return pyb::make_tuple(indptr, indices, data);
    }
  }

  std::unique_ptr<Simulation> sim_;
  std::vector<int> pinned_;
  std::shared_ptr<PythonTargets> targets_;
  int reoriented_ = 0;
  std::unique_ptr<HessianLayout> layout_;
  std::vector<int> scatter_;
};

}  // namespace
}  // namespace snh::py
namespace pybind11::detail {
template <>
struct type_caster<snh::py::PySimulation> : snh::py::checked_caster<snh::py::PySimulation> {};
}  // namespace pybind11::detail
namespace snh::py {
namespace {

/// A scene from a path (its relative paths resolve against the file's directory) or from a dict (its JSON
/// text; its relative paths resolve against base_dir, by default the working directory).
Scene scene_of(const pyb::handle& obj, const std::optional<std::filesystem::path>& base_dir) {
  if (pyb::isinstance<pyb::dict>(obj)) {
    // NumPy scalars and arrays (np.int64(2), np.array([0, 1, 0])) are written as the numbers and lists they
    // hold; anything else JSON cannot hold is a ValueError naming its type.
    const pyb::cpp_function plain([](const pyb::handle& value) -> pyb::object {
      if (pyb::hasattr(value, "tolist") && pyb::hasattr(value, "dtype")) return value.attr("tolist")();
      throw pyb::value_error(fmt::format("scene: a value of type {} cannot be written as JSON (give numbers, strings, lists "
                                         "and dicts)",
                                         std::string(pyb::str(pyb::type::handle_of(value).attr("__name__")))));
    });
    const std::string text = pyb::module_::import("json").attr("dumps")(obj, pyb::arg("default") = plain).cast<std::string>();
    const std::filesystem::path source = base_dir ? *base_dir / "scene" : std::filesystem::path("scene");
    return parse_scene(read_scene_json(text, source.string()), source);
  }
  require(!base_dir, "base_dir is for a scene given as a dict: a scene file's paths resolve against its own directory");
  if (!pyb::isinstance<pyb::str>(obj) && !pyb::hasattr(obj, "__fspath__"))
    throw pyb::type_error(fmt::format("scene must be a path (str or os.PathLike) or a dict, got {}",
                                      std::string(pyb::str(pyb::type::handle_of(obj).attr("__name__")))));
  return load_scene(obj.cast<std::filesystem::path>());
}

/// Runs the scene on a worker thread while this one, holding the GIL in short turns, lets Python see
/// Ctrl-C: a KeyboardInterrupt asks the run to stop as snh run's SIGINT does (the frames so far and the
/// stats are kept), and is raised once the run has stopped.
SceneResult run_interruptibly(const BuiltScene& scene, std::ostream& log) {
  SceneResult result;
  std::exception_ptr error;
  std::atomic<bool> done{false};
  request_stop(0);
  std::thread worker([&] {
    try {
      result = run_scene(scene, log);
    } catch (...) {
      error = std::current_exception();
    }
    done = true;
  });
  bool interrupted = false;
  while (!done) {
    {
      pyb::gil_scoped_release release;
      for (int i = 0; i < 20 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (!interrupted && PyErr_CheckSignals() != 0) {
      interrupted = true;
      request_stop(SIGINT);
    }
  }
  worker.join();
  request_stop(0);
  if (interrupted) throw pyb::error_already_set();
  if (error) std::rethrow_exception(error);
  return result;
}

pyb::dict run_scene_py(const pyb::handle& scene_obj, std::optional<std::filesystem::path> base_dir,
                       std::optional<std::filesystem::path> out, bool force, bool resume, bool keep_going, bool report, bool quiet,
                       int threads, bool check) {
  Scene parsed = scene_of(scene_obj, base_dir);
  if (out) {
    require(!out->empty(), "out must not be empty");
    parsed.output.dir = *out;
  }
  parsed.run.resume = resume;
  parsed.run.keep_going = keep_going;
  parsed.run.command_line = "snh.run_scene (Python)";
  require(threads >= 0 && threads <= 1024, fmt::format("threads must be from 0 to 1024, got {}", threads));
  const int previous_threads = omp_get_max_threads();
  if (threads > 0) omp_set_num_threads(threads);
  std::ostringstream discard;
  std::ostream& log = quiet ? static_cast<std::ostream&>(discard) : std::cout;
  BuiltScene built;
  SceneResult r;
  try {
    built = build_scene(parsed);  // before the output directory is touched: a scene that cannot run writes nothing
    built.scene.run.lock = std::make_shared<RunDirectoryLock>(built.scene.output.dir, force);
    r = run_interruptibly(built, log);
  } catch (...) {
    omp_set_num_threads(previous_threads);
    throw;
  }
  omp_set_num_threads(previous_threads);
  const Scene& scene = built.scene;
  log.flush();
  pyb::dict d;
  d["out"] = scene.output.dir;
  d["frames"] = static_cast<int>(r.frames.size());
  d["all_converged"] = r.all_converged;
  d["failure"] = r.failure;
  d["warnings"] = r.warnings;
  d["unconverged_frames"] = r.unconverged;
  d["total_seconds"] = r.total_seconds;
  d["element"] = std::string(to_string(r.element));
  d["final_positions"] = positions_array(r.final_positions);
  d["final_surface"] = pyb::none();
  d["surface_triangles"] = pyb::none();
  if (const Flesh* flesh = built.body->flesh.get(); flesh && r.final_positions.size() > 0) {
    // The character's skin, as the OBJ and USD frames hold it: the render surface embedded in the volume.
    const Eigen::Matrix3Xd skin = flesh_surface(*flesh, r.final_positions);
    d["final_surface"] = positions_array(Eigen::Map<const Eigen::VectorXd>(skin.data(), skin.size()));
    const Eigen::Matrix3Xi& t = flesh->model.triangles;
    pyb::array_t<std::int32_t> tri({static_cast<pyb::ssize_t>(t.cols()), pyb::ssize_t{3}});
    std::copy(t.data(), t.data() + t.size(), tri.mutable_data());
    d["surface_triangles"] = tri;
  }
  d["report"] = pyb::none();
#ifdef SNH_PYTHON_REPORT
  // As snh run: a report that cannot be written is a warning; the run's own results stay.
  if (report) try {
      d["report"] = write_report(scene.output.dir).index;
    } catch (const std::exception& e) {
      if (PyErr_WarnEx(PyExc_RuntimeWarning, fmt::format("the report was not written: {}", e.what()).c_str(), 1) != 0)
        throw pyb::error_already_set();
    }
#else
  (void)report;
#endif
  built.scene.run.lock.reset();
  if (!r.all_converged && check) throw std::runtime_error(r.failure);
  return d;
}

}  // namespace

void add_simulation(pyb::module_& m) {
  using namespace pyb::literals;
  pyb::class_<PySimulation>(m, "Simulation",
                            "A mesh of one material stepped quasi-statically, by backward Euler, BDF2 or TR-BDF2 (projected Newton); the "
                            "pinned vertices follow targets set from Python before each step.")
      .def(pyb::init<const pyb::handle&, const pyb::handle&, const pyb::handle&, const pyb::handle&, const std::string&,
                     double, double, const pyb::handle&, double, double, const pyb::handle&, const pyb::handle&, const std::string&, bool, double,
                     double, double, int, int, const std::string&, const pyb::object&>(),
           "vertices"_a, "cells"_a, "material"_a, "pinned"_a = pyb::none(), pyb::kw_only(), "integrator"_a = "quasi_static",
           "dt"_a = 0.01, "density"_a = 1.0, "gravity"_a = std::vector<double>{0.0, 0.0, 0.0}, "mass_damping"_a = 0.0,
           "stiffness_damping"_a = 0.0, "initial"_a = pyb::none(), "initial_velocity"_a = pyb::none(), "solver"_a = "auto", "reuse_factor"_a = true,
           "tolerance"_a = 1e-3, "step_tolerance"_a = 0.0, "relative_step_tolerance"_a = 0.0, "max_iterations"_a = 50,
           "step_halvings"_a = 4, "projection"_a = "clamp", "first_guess"_a = pyb::none(),
           "vertices (n, 3), cells (m, 4) tets or (m, 8) hexes (checked as a mesh file is), an snh.Material, pinned "
           "vertex indices (k,). integrator quasi_static, backward_euler, bdf2 or tr_bdf2 (time step dt; BDF2 and TR-BDF2 keep the motion "
           "backward Euler damps; BDF2's first step is backward Euler, TR-BDF2 makes two solves a step); density, gravity (3,), "
           "Rayleigh mass/stiffness damping; initial positions (n, 3) and velocities (n, 3; dynamic only); the linear solver (auto: by size, as scenes; cholmod, "
           "ldlt, pcg, mg for hex lattices, amg); Newton's "
           "stopping rule: ||g|| < tolerance (the paper programs' 1e-3), or the Newton step below step_tolerance (a "
           "length) or below relative_step_tolerance of the solve's own motion; step_halvings: a dynamic step whose "
           "solve fails is retried in halves this many times deep; first_guess(x, t) -> (n, 3): the first "
           "quasi-static step's starting positions (later ones extrapolate).")
      .def_property_readonly("positions", [](const PySimulation& s) { return positions_array(s.sim_->x()); },
                             "The current positions (n, 3), a copy.")
      .def_property_readonly("velocities", [](const PySimulation& s) { return positions_array(s.sim_->v()); })
      .def_property_readonly("time", [](const PySimulation& s) { return s.sim_->time(); })
      .def_property_readonly("steps", [](const PySimulation& s) { return s.sim_->steps(); }, "Solves completed (a TR-BDF2 step, of two solves, counts once).")
      .def_property_readonly("pinned", [](const PySimulation& s) { return pyb::array_t<int>(static_cast<pyb::ssize_t>(s.pinned_.size()), s.pinned_.data()); })
      .def_property_readonly("reoriented", [](const PySimulation& s) { return s.reoriented_; },
                             "Cells given with negative rest volume, turned round.")
      .def_property_readonly("rest_volume", [](const PySimulation& s) { return s.sim_->rest_volume(); })
      .def_property_readonly("free_dofs", [](const PySimulation& s) {
        std::vector<int> free;
        const auto& idx = s.sim_->problem().dofs().free_index();
        for (std::size_t d = 0; d < idx.size(); ++d)
          if (idx[d] >= 0) free.push_back(static_cast<int>(d));
        return pyb::array_t<int>(static_cast<pyb::ssize_t>(free.size()), free.data());
      }, "The DOFs (3 v + axis) Newton solves for, increasing.")
      .def_property("targets", &PySimulation::targets, &PySimulation::set_targets,
                    "The pinned vertices' targets (k, 3), in the order of pinned; set them before each step.")
      .def("set_targets", &PySimulation::set_targets, "targets"_a)
      .def("step", &PySimulation::step, "t"_a = pyb::none(), "check"_a = true,
           "One solve to time t (default: time + dt, or time + 1 quasi-statically) with the pins at their targets; "
           "returns the step's stats (a dict). RuntimeError with Newton's reason if it does not converge (check=False "
           "returns the stats instead, converged False). Ctrl-C interrupts it between Newton iterations "
           "(KeyboardInterrupt; the state stays where the step started).")
      .def("energy", &PySimulation::energy, "x"_a = pyb::none(),
           "The elastic energy at positions x (n, 3) (default: the current ones); +inf outside the domain.")
      .def("gradient", &PySimulation::gradient, "x"_a = pyb::none(), "dE/dx at x, (n, 3), every vertex.")
      .def("hessian", &PySimulation::hessian, "x"_a = pyb::none(), "projection"_a = "none",
           "d2E/dx2 at x over every DOF (3 v + axis), symmetric: a scipy.sparse CSR matrix, or (indptr, indices, data) "
           "without SciPy. projection: none (the true Hessian), clamp or abs per element.");

  m.def("run_scene", &run_scene_py, "scene"_a, pyb::kw_only(), "base_dir"_a = pyb::none(), "out"_a = pyb::none(), "force"_a = false,
        "resume"_a = false, "keep_going"_a = false, "report"_a = true, "quiet"_a = false, "threads"_a = 0, "check"_a = true,
        "Runs a scene (a file path, or a dict with the file's keys: a flesh scene is snh flesh) as snh run does, into out "
        "(default: the scene's output.dir): frames, stats.json, stats.csv, checkpoint and the report. A dict's relative "
        "paths resolve against base_dir (default: the working directory), a file's against its directory. Returns a dict "
        "(out, frames, all_converged, failure, unconverged_frames, total_seconds, element, final_positions: the volume's vertices, and for a "
        "flesh scene final_surface and surface_triangles: the character's skin; report). ValueError for a bad "
        "scene, RuntimeError when a frame fails (check=False: returned in the dict; keep_going=True: frames that do not converge are "
        "written, marked in stats.json, and the run goes on to the end before that error), KeyboardInterrupt on Ctrl-C (the "
        "frames so far kept).");
}

}  // namespace snh::py
