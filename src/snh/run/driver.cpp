#include "snh/run/driver.hpp"

#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <optional>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/run/checkpoint.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/run/output.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace snh {
namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// stats.json and stats.csv of the run so far.
void write_stats(const RunPlan& plan, const RunResult& r, const std::string& status, const json* extra = nullptr) {
  const RecordTable& table = *plan.table;
  json j = plan.settings;
  j["snh_version"] = SNH_VERSION;
  j["status"] = status;
  j["all_converged"] = status == "finished" ? r.all_converged : false;
  j["failure"] = r.failure;
  j["interrupted_by_signal"] = r.interrupted_by;
  j["total_seconds"] = r.total_seconds;
  j["peak_memory_mib"] = r.peak_memory_mib;
  add_totals(table, r.records, j);
  if (extra)
    for (auto it = extra->begin(); it != extra->end(); ++it) j[it.key()] = it.value();
  json records = json::array();
  for (const StepRecord& s : r.records) records.push_back(to_json(table, s));
  j[table.records] = records;
  j["schema"] = schema_json(table);
  write_atomically(plan.out / "stats.json", [&](std::ostream& o) { o << j.dump(2) << "\n"; });
  write_atomically(plan.out / "stats.csv", [&](std::ostream& o) {
    o << csv_header(table) << "\n";
    for (const StepRecord& s : r.records) o << csv_row(table, s) << "\n";
  });
}

/// Min det F, inverted-element count and volume ratio of the current state.
void record_deformation(const ElasticTerm::Deformation& d, double rest_volume, StepRecord& r) {
  r.min_J = d.min_J.minCoeff();
  r.inverted = static_cast<int>((d.min_J.array() <= 0.0).count());
  r.volume_ratio = d.volume / rest_volume;
}

/// Whether every number of a record that the log line and the stats show is finite.
bool finite_record(const StepRecord& r) {
  for (double v : {r.residual, r.energy, r.volume_ratio, r.min_J, r.elastic_energy, r.kinetic_energy, r.gravity_energy,
                   r.total_energy, r.surface_volume_ratio, r.lbs_volume_ratio})
    if (!std::isfinite(v)) return false;
  return true;
}

}  // namespace

RunResult run_simulation(Simulation& sim, const RunPlan& plan, std::ostream& log) {
  const auto t_start = Clock::now();
  const RecordTable& table = *plan.table;
  const std::string word = table.index;  // "step" or "frame"
  RunResult result;
  const std::shared_ptr<RunDirectoryLock> lock = plan.lock ? plan.lock : std::make_shared<RunDirectoryLock>(plan.out);

  // A resume is checked before any work: the checkpoint (intact, these settings, this mesh), the frames it
  // keeps and their history. A fresh run starts from an empty directory of ours.
  // A run whose memory estimate exceeds what this process may use is refused before any work.
  const ProblemSize size = problem_size(sim.mesh());
  const std::string solver(sim.solver().name());  // what "auto" chose
  check_memory(size, solver, fmt::format("{} mesh", to_string(sim.mesh().type)));

  std::optional<Checkpoint> resume_from;
  if (plan.resume) {
    resume_from = checkpoint_for_resume(plan.out, plan.fingerprint, sim.x().size());
    if (resume_from->step > plan.frames)
      throw std::invalid_argument(fmt::format("cannot resume: the checkpoint in {} is after {} {}, beyond the {} of this run",
                                              plan.out.string(), word, resume_from->step, plan.frames));
    check_kept_frames(plan.out, resume_from->step, plan.write_vtu);
    for (const json& j : history_for_resume(plan.out, table.records, resume_from->step + (table.has_initial ? 1 : 0)))
      result.records.push_back(from_json(table, j));
  } else {
    (void)clear_previous_run(plan.out, *lock);
  }
  write_stats(plan, result, "running");

  if (plan.header) plan.header(log);
  log.flush();
  FrameWriter frames(plan.out, sim.mesh(), plan.write_vtu, sim.kinematic_vertices());
  int first = 1;
  if (resume_from) {
    sim.restore({.x = resume_from->x, .aux = resume_from->aux, .time = resume_from->time,
                 .steps = resume_from->step * plan.substeps});
    frames.adopt_written(resume_from->step, [&](int i) { return i * plan.frame_duration; });
    first = resume_from->step + 1;
    log << fmt::format("resuming after {} {} (checkpoint in {})\n", word, resume_from->step, plan.out.string());
    log.flush();
  }

  // The run's progress on disk, what a report and a resume read: frames.pvd, stats.json and stats.csv,
  // and the checkpoint of the last converged frame. Each is a file replaced as a whole (a rename over the
  // last one, which ext4 follows with a flush of the new file, and the stats grow with the run), so it is
  // written after the first frame of this process, then once plan.progress_interval has
  // passed since the last time, and whenever the run ends, however it ends (finish, the out-of-memory
  // path, and the guard below for any exception). A run killed outright loses at most that interval: its
  // later frames stay on disk and a resume from the checkpoint writes them again.
  std::optional<Checkpoint> pending;  // the last converged frame's, not yet on disk
  bool unsaved = false;               // frames or records since the progress was last written
  auto last_progress = Clock::now();
  auto write_progress = [&](const std::string& status, const json* extra) {
    frames.write_series();
    write_stats(plan, result, status, extra);
    if (pending) write_checkpoint(plan.out, *pending);
    pending.reset();
    unsaved = false;
    last_progress = Clock::now();
  };
  // However the run leaves by an exception (a frame that cannot be written, out of memory, a solver's
  // error), the progress not yet on disk is written first, as far as it can be.
  struct WriteOnException {
    std::function<void()> write;
    int uncaught = std::uncaught_exceptions();
    ~WriteOnException() {
      if (std::uncaught_exceptions() > uncaught) try {
          write();
        } catch (const std::exception&) {  // the exception on its way matters more
        }
    }
  } write_on_exception{[&] {
    if (unsaved) write_progress("running", nullptr);
  }};
  auto frame_failure = [&](int index, const char* what) {
    return fmt::format("{} {}: {} ({}stats.json and checkpoint.bin are kept: --resume continues once the output can be "
                       "written)",
                       word, index, what, index > 0 ? fmt::format("frames 000 to {:03d}, ", index - 1) : "");
  };
  auto write_frame = [&](int index, const ElasticTerm::Deformation& d) {
    try {
      frames.write(index, index * plan.frame_duration, sim.x(), d);
      unsaved = true;
      if (plan.write_frame) plan.write_frame(index, index * plan.frame_duration, sim.x());
    } catch (const WriteError& e) {
      throw WriteError(frame_failure(index, e.what()));
    } catch (const OutputRefused& e) {  // something that is not a regular file where a frame goes
      throw OutputRefused(frame_failure(index, e.what()));
    }
  };
  auto finish = [&](const std::string& status) {
    result.total_seconds = since(t_start);
    result.peak_memory_mib = peak_memory_mib();
    json extra = json::object();
    if (plan.finish) plan.finish(extra);
    write_progress(status, &extra);
    if (plan.summary) log << plan.summary(result) << "\n";
    log.flush();
    return result;
  };

  if (!resume_from) {
    const auto t0 = Clock::now();
    const ElasticTerm::Deformation d = sim.elastic().deformation(sim.x());
    write_frame(0, d);
    if (table.has_initial) {
      StepRecord r0;
      record_deformation(d, sim.rest_volume(), r0);
      if (plan.fill) plan.fill(r0, nullptr);
      if (!std::isfinite(sim.elastic().energy(sim.x()))) {
        Eigen::Index worst = 0;
        d.min_J.minCoeff(&worst);
        r0.converged = false;
        r0.failure = fmt::format("the initial state is outside the domain of {} ({} element(s) with J <= 0; min J = {:.4g})",
                                 name_of(sim.elastic().material(worst)), r0.inverted, r0.min_J);
        result.all_converged = false;
        result.failure = r0.failure;
      }
      r0.wall_seconds = since(t0);
      result.records.push_back(r0);
      if (plan.line) log << plan.line(r0) << "\n";
      log.flush();
      if (!result.all_converged) return finish("stopped");
    }
  }

  const NewtonOptions& base = sim.setup().newton;
  bool stopped = false;
  for (int frame = first; frame <= plan.frames; ++frame) {
    if (stop_requested()) {
      stopped = true;
      break;
    }
    const auto t_frame = Clock::now();
    int substep = 1;
    NewtonOptions newton = base;
    newton.should_stop = [] { return stop_requested(); };
    if (plan.live_progress && plan.live)
      newton.on_iteration = [&](int it, double r) {
        if (base.on_iteration) base.on_iteration(it, r);
        log << "\r\x1b[2K" << plan.live(frame, substep, it, r);
        log.flush();
      };
    // Out of memory (the linear solver's allocation failed, or any other): the stats say so, the frames
    // and the checkpoint so far are kept, and the run ends with one OutOfMemoryError naming the estimate.
    auto out_of_memory = [&](const std::string& what) {
      if (plan.live_progress && plan.live) log << "\r\x1b[2K";
      log.flush();
      std::string message = out_of_memory_message(fmt::format("{} {} ({})", word, frame, what), size, solver);
      if (frame > 1) message += fmt::format("; frames 000 to {:03d} and checkpoint.bin are kept", frame - 1);
      result.all_converged = false;
      result.failure = message;
      result.total_seconds = since(t_start);
      result.peak_memory_mib = peak_memory_mib();
      try {
        write_progress("stopped", nullptr);
      } catch (const std::exception&) {  // the message matters more than the stats
      }
      throw OutOfMemoryError(message);
    };
    const SimulationState before = sim.state();
    StepReport rep;
    try {
      rep = sim.advance((frame - 1) * plan.frame_duration, plan.substep, plan.substeps, &newton,
                        [&](int k) { substep = k; });
    } catch (const OutOfMemoryError& e) {
      out_of_memory(e.what());
    } catch (const std::bad_alloc&) {
      out_of_memory("an allocation failed");
    }
    if (plan.live_progress && plan.live) log << "\r\x1b[2K";
    if (rep.interrupted) {  // the frame is abandoned: the state is the last completed frame's
      stopped = true;
      break;
    }
    StepRecord r;
    r.index = frame;
    r.time = frame * plan.frame_duration;
    r.substeps = plan.substeps;
    r.converged = rep.converged;
    r.newton_iterations = rep.newton.iterations;
    r.line_search_steps = rep.newton.line_search_steps;
    r.linear_iterations = rep.newton.linear_iterations;
    r.factorizations = rep.newton.factorizations;
    r.true_hessian_steps = rep.newton.true_hessian_steps;
    r.residual = rep.newton.residual;
    r.energy = rep.newton.energy;
    r.assembly_seconds = rep.newton.assembly_seconds;
    r.solve_seconds = rep.newton.solve_seconds;
    r.residuals = rep.newton.residuals;
    if (!rep.converged) r.failure = plan.failure ? plan.failure(rep) : rep.failure;
    const ElasticTerm::Deformation d = sim.elastic().deformation(sim.x());
    record_deformation(d, sim.rest_volume(), r);
    if (plan.fill) plan.fill(r, &rep);
    // No NaN or Inf reaches a frame, the records or the screen: a state (or its energies, residual, volume)
    // that is not finite ends the run at the last completed frame, whose files and checkpoint stay.
    const SimulationState after = sim.state();
    if (!after.x.allFinite() || !after.aux.allFinite() || !finite_record(r)) {
      sim.restore(before);
      result.all_converged = false;
      result.failure = fmt::format("{} {}: the state is not finite (NaN or Inf) after t = {:g}; stopped, {}s 000 to {:03d} kept",
                                   word, frame, r.time, word, frame - 1);
      return finish("stopped");
    }
    write_frame(frame, d);
    r.wall_seconds = since(t_frame);
    result.records.push_back(r);
    if (plan.line) log << plan.line(r) << "\n";
    log.flush();
    if (!r.converged) {
      result.all_converged = false;
      result.failure = fmt::format("{} {}, {}", word, frame, r.failure);
      return finish("stopped");
    }
    // Everything needed to resume after this frame: the stats so far and the exact state.
    result.total_seconds = since(t_start);
    SimulationState s = sim.state();
    pending = Checkpoint{.fingerprint = plan.fingerprint, .step = frame, .time = r.time, .x = std::move(s.x), .aux = std::move(s.aux)};
    unsaved = true;
    if (frame == first || since(last_progress) >= plan.progress_interval) write_progress("running", nullptr);
  }
  if (stopped) {
    result.interrupted_by = stop_signal();
    result.all_converged = false;
    result.failure = fmt::format("interrupted by signal {} after {} {}", result.interrupted_by, word,
                                 result.records.empty() ? 0 : result.records.back().index);
    return finish("interrupted");
  }
  return finish("finished");
}

}  // namespace snh
