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
  j["unconverged_frames"] = r.unconverged;
  if (!r.failed_frame.empty()) j["failed_frame"] = r.failed_frame;
  j["interrupted_by_signal"] = r.interrupted_by;
  j["total_seconds"] = r.total_seconds;
  j["peak_memory_mib"] = r.peak_memory_mib;
  j["warnings"] = r.warnings;
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
                   r.total_energy, r.surface_volume_ratio, r.lbs_volume_ratio, r.lbs_distance, r.tip_distance})
    if (!std::isfinite(v)) return false;
  return true;
}

/// Adds the run's progress not yet on disk when an exception leaves the scope it guards (a frame that cannot
/// be written, out of memory, a solver's error), as far as it can be written.
struct WriteOnException {
  std::function<void()> write;
  int uncaught = std::uncaught_exceptions();
  ~WriteOnException() {
    if (std::uncaught_exceptions() > uncaught) try {
        write();
      } catch (const std::exception&) {  // the exception on its way matters more
      }
  }
};

/// The size the memory estimate needs: the mesh's, and whether it has contact terms.
ProblemSize problem_size(const Simulation& sim) {
  ProblemSize size = problem_size(sim.mesh());
  size.contact = sim.has_contact();
  return size;
}

/// One run of a plan (run_simulation): what its stages share.
class RunLoop {
 public:
  RunLoop(Simulation& sim, const RunPlan& plan, std::ostream& log)
      : sim_(sim),
        plan_(plan),
        log_(log),
        table_(*plan.table),
        word_(table_.index),
        lock_(plan.lock ? plan.lock : std::make_shared<RunDirectoryLock>(plan.out)),
        size_(problem_size(sim)),
        solver_(sim.solver().name()) {}

  RunResult run() {
    result_.warnings = plan_.warnings;
    prepare();
    const WriteOnException guard{[this] {
      if (unsaved_) write_progress("running", nullptr);
    }};
    if (!resume_from_ && !initial_frame()) return finish("stopped");
    for (int frame = first_; frame <= plan_.frames; ++frame) {
      if (stop_requested()) return interrupted();
      const Outcome o = step(frame);
      if (o == Outcome::interrupted) return interrupted();
      if (o == Outcome::stopped) return finish("stopped");
    }
    return finish("finished");
  }

 private:
  enum class Outcome { next, stopped, interrupted };

  /// Before any work: the memory estimate (a run that cannot fit is refused), a resume's checks (the
  /// checkpoint intact, for these settings and this mesh; the frames it keeps and their history) or, for a
  /// fresh run, the directory cleared of a previous run of ours; then the stats say "running", the header,
  /// and a resumed state restored.
  void prepare() {
    check_memory(size_, solver_, fmt::format("{} mesh", to_string(sim_.mesh().type)));
    if (plan_.resume) {
      resume_from_ = checkpoint_for_resume(plan_.out, plan_.fingerprint, sim_.x().size());
      if (resume_from_->step > plan_.frames)
        throw std::invalid_argument(fmt::format("cannot resume: the checkpoint in {} is after {} {}, beyond the {} of this run",
                                                plan_.out.string(), word_, resume_from_->step, plan_.frames));
      check_kept_frames(plan_.out, resume_from_->step, plan_.write_vtu);
      for (const json& j : history_for_resume(plan_.out, table_.records, resume_from_->step + (table_.has_initial ? 1 : 0))) {
        result_.records.push_back(from_json(table_, j));
        const StepRecord& r = result_.records.back();
        if (!r.converged) not_converged(r);  // a frame that a --keep-going run went past
      }
    } else {
      (void)clear_previous_run(plan_.out, *lock_);
    }
    write_stats(plan_, result_, "running");
    if (plan_.header) plan_.header(log_);
    log_.flush();
    frames_.emplace(plan_.out, sim_.mesh(), plan_.write_vtu, sim_.kinematic_vertices());
    if (resume_from_) {
      sim_.restore({.x = resume_from_->x, .aux = resume_from_->aux, .time = resume_from_->time,
                    .steps = resume_from_->step * plan_.substeps});
      frames_->adopt_written(resume_from_->step, [&](int i) { return i * plan_.frame_duration; },
                             [&](int i) {  // a frame that a --keep-going run went past stays marked
                               for (const StepRecord& r : result_.records)
                                 if (r.index == i && !r.converged) return unconverged_note(r);
                               return std::string();
                             });
      first_ = resume_from_->step + 1;
      log_ << fmt::format("resuming after {} {} (checkpoint in {})\n", word_, resume_from_->step, plan_.out.string());
      log_.flush();
    }
  }

  // The run's progress on disk, what a report and a resume read: frames.pvd, stats.json and stats.csv, and
  // the checkpoint of the last converged frame. Each is a file replaced as a whole (a rename over the last
  // one, which ext4 follows with a flush of the new file, and the stats grow with the run), so it is written
  // after the first frame of this process, then once plan.progress_interval has passed since the last time,
  // and whenever the run ends, however it ends (finish, the out-of-memory path, and the guard in run() for
  // any exception). A run killed outright loses at most that interval: its later frames stay on disk and a
  // resume from the checkpoint writes them again.
  void write_progress(const std::string& status, const json* extra) {
    frames_->write_series();
    write_stats(plan_, result_, status, extra);
    if (pending_) write_checkpoint(plan_.out, *pending_);
    pending_.reset();
    unsaved_ = false;
    last_progress_ = Clock::now();
  }

  /// Frame `index`'s files (NNN.obj, NNN.vtu, and the plan's own; `prefix` and `note` as FrameWriter::write
  /// takes them); a failure names the frame and what is kept.
  void write_frame(int index, const ElasticTerm::Deformation& d, const std::string& prefix = "", const std::string& note = "") {
    const auto failure = [&](const char* what) {
      return fmt::format("{} {}: {} ({}stats.json and checkpoint.bin are kept: --resume continues once the output can be "
                         "written)",
                         word_, index, what, index > 0 ? fmt::format("frames 000 to {:03d}, ", index - 1) : "");
    };
    try {
      frames_->write(index, index * plan_.frame_duration, sim_.x(), d, prefix, note);
      unsaved_ = true;
      if (plan_.write_frame) plan_.write_frame(index, index * plan_.frame_duration, sim_.x(), prefix);
    } catch (const WriteError& e) {
      throw WriteError(failure(e.what()));
    } catch (const OutputRefused& e) {  // something that is not a regular file where a frame goes
      throw OutputRefused(failure(e.what()));
    }
  }

  RunResult finish(const std::string& status) {
    if (const InsideOut io = inside_out_frames(result_.records); io.frames > 0)
      result_.warnings.push_back(fmt::format("{} {}{} converged with elements turned inside out (at most {}, in {} {})", io.frames,
                                             word_, io.frames == 1 ? "" : "s", io.most, word_, io.worst));
    result_.total_seconds = since(t_start_);
    result_.peak_memory_mib = peak_memory_mib();
    json extra = json::object();
    if (plan_.finish) plan_.finish(result_, extra);
    write_progress(status, &extra);
    if (plan_.summary) log_ << plan_.summary(result_) << "\n";
    log_.flush();
    return result_;
  }

  /// What frames.pvd says before a frame that did not converge.
  std::string unconverged_note(const StepRecord& r) const { return fmt::format("{} {} did not converge: {}", word_, r.index, r.failure); }

  /// A frame that did not converge: the run's result says so (its failure names the first such frame).
  void not_converged(const StepRecord& r) {
    result_.all_converged = false;
    result_.unconverged.push_back(r.index);
    if (result_.failure.empty()) result_.failure = fmt::format("{} {}, {}", word_, r.index, r.failure);
    if (!plan_.keep_going) result_.failed_frame = fmt::format("{}{:03d}.obj", kFailedPrefix, r.index);
  }

  RunResult interrupted() {
    result_.interrupted_by = stop_signal();
    result_.all_converged = false;
    result_.failure = fmt::format("interrupted by signal {} after {} {}", result_.interrupted_by, word_,
                                  result_.records.empty() ? 0 : result_.records.back().index);
    return finish("interrupted");
  }

  /// Frame 0, the initial state (a fresh run): its files, and its record where the table has one. False when
  /// the initial state is outside an energy's domain (the run stops there).
  bool initial_frame() {
    const auto t0 = Clock::now();
    const ElasticTerm::Deformation d = sim_.elastic().deformation(sim_.x());
    write_frame(0, d);
    if (!table_.has_initial) return true;
    StepRecord r0;
    record_deformation(d, sim_.rest_volume(), r0);
    if (plan_.fill) plan_.fill(r0, nullptr);
    if (!std::isfinite(sim_.elastic().energy(sim_.x()))) {
      Eigen::Index worst = 0;
      d.min_J.minCoeff(&worst);
      r0.converged = false;
      r0.failure = fmt::format("the initial state is outside the domain of {} ({} element(s) with J <= 0; min J = {:.4g})",
                               name_of(sim_.elastic().material(worst)), r0.inverted, r0.min_J);
      result_.all_converged = false;
      result_.failure = r0.failure;
    }
    r0.wall_seconds = since(t0);
    result_.records.push_back(r0);
    if (plan_.line) log_ << plan_.line(r0) << "\n";
    log_.flush();
    return result_.all_converged;
  }

  /// Out of memory (the linear solver's allocation failed, or any other) in frame `frame`: the stats say so,
  /// the frames and the checkpoint so far are kept, and the run ends with one OutOfMemoryError naming the
  /// estimate.
  [[noreturn]] void out_of_memory(int frame, const std::string& what) {
    if (plan_.live_progress && plan_.live) log_ << "\r\x1b[2K";
    log_.flush();
    std::string message = out_of_memory_message(fmt::format("{} {} ({})", word_, frame, what), size_, solver_);
    if (frame > 1) message += fmt::format("; frames 000 to {:03d} and checkpoint.bin are kept", frame - 1);
    result_.all_converged = false;
    result_.failure = message;
    result_.total_seconds = since(t_start_);
    result_.peak_memory_mib = peak_memory_mib();
    try {
      write_progress("stopped", nullptr);
    } catch (const std::exception&) {  // the message matters more than the stats
    }
    throw OutOfMemoryError(message);
  }

  /// The record of a frame from its solve's report.
  StepRecord record_of(int frame, const StepReport& rep) const {
    StepRecord r;
    r.index = frame;
    r.time = frame * plan_.frame_duration;
    r.substeps = plan_.substeps + rep.halvings;
    r.halvings = rep.halvings;
    r.converged = rep.converged;
    r.newton_iterations = rep.newton.iterations;
    r.line_search_steps = rep.newton.line_search_steps;
    r.linear_iterations = rep.newton.linear_iterations;
    r.factorizations = rep.newton.factorizations;
    r.true_hessian_steps = rep.newton.true_hessian_steps;
    r.residual = rep.newton.residual;
    r.newton_step = rep.newton.last_step;
    r.energy = rep.newton.energy;
    r.assembly_seconds = rep.newton.assembly_seconds;
    r.solve_seconds = rep.newton.solve_seconds;
    r.residuals = rep.newton.residuals;
    if (!rep.converged) r.failure = plan_.failure ? plan_.failure(rep) : rep.failure;
    return r;
  }

  /// Frame `frame`: its substeps solved, its record, its files, and the checkpoint after it (on disk at the
  /// next progress write).
  Outcome step(int frame) {
    const auto t_frame = Clock::now();
    int substep = 1;
    const NewtonOptions& base = sim_.setup().newton;
    NewtonOptions newton = base;
    newton.should_stop = [] { return stop_requested(); };
    if (plan_.live_progress && plan_.live)
      newton.on_iteration = [&](int it, double r) {
        if (base.on_iteration) base.on_iteration(it, r);
        log_ << "\r\x1b[2K" << plan_.live(frame, substep, it, r);
        log_.flush();
      };
    const SimulationState before = sim_.state();
    StepReport rep;
    try {
      rep = sim_.advance((frame - 1) * plan_.frame_duration, plan_.substep, plan_.substeps, &newton, [&](int k) { substep = k; });
    } catch (const OutOfMemoryError& e) {
      out_of_memory(frame, e.what());
    } catch (const std::bad_alloc&) {
      out_of_memory(frame, "an allocation failed");
    }
    if (plan_.live_progress && plan_.live) log_ << "\r\x1b[2K";
    if (rep.interrupted) return Outcome::interrupted;  // the frame is abandoned: the state is the last completed frame's
    StepRecord r = record_of(frame, rep);
    const ElasticTerm::Deformation d = sim_.elastic().deformation(sim_.x());
    record_deformation(d, sim_.rest_volume(), r);
    if (plan_.fill) plan_.fill(r, &rep);
    // No NaN or Inf reaches a frame, the records or the screen: a state (or its energies, residual, volume)
    // that is not finite ends the run at the last completed frame, whose files and checkpoint stay.
    const SimulationState after = sim_.state();
    if (!after.x.allFinite() || !after.aux.allFinite() || !finite_record(r)) {
      sim_.restore(before);
      result_.all_converged = false;
      result_.failure = fmt::format("{} {}: the state is not finite (NaN or Inf) after t = {:g}; stopped, {}s 000 to {:03d} kept",
                                    word_, frame, r.time, word_, frame - 1);
      return Outcome::stopped;
    }
    // A frame that did not converge is no result. Where the run stops at it, its state (the last Newton
    // iterate) is written as failed_NNN, outside the series, the caches and the report's frames; a run that
    // goes on (keep_going) must keep its frames in order, so it is written as NNN, marked in frames.pvd and
    // by the caches.
    const bool stops_here = !r.converged && !plan_.keep_going;
    write_frame(frame, d, stops_here ? kFailedPrefix : "", r.converged ? "" : unconverged_note(r));
    r.wall_seconds = since(t_frame);
    result_.records.push_back(r);
    if (plan_.line) log_ << plan_.line(r) << "\n";
    log_.flush();
    if (!r.converged) {
      not_converged(r);
      if (!plan_.keep_going) return Outcome::stopped;
    }
    // Everything needed to resume after this frame: the stats so far and the exact state.
    result_.total_seconds = since(t_start_);
    SimulationState s = sim_.state();
    pending_ = Checkpoint{.fingerprint = plan_.fingerprint, .step = frame, .time = r.time, .x = std::move(s.x), .aux = std::move(s.aux)};
    unsaved_ = true;
    if (frame == first_ || since(last_progress_) >= plan_.progress_interval) write_progress("running", nullptr);
    return Outcome::next;
  }

  const Clock::time_point t_start_ = Clock::now();
  Simulation& sim_;
  const RunPlan& plan_;
  std::ostream& log_;
  const RecordTable& table_;
  const std::string word_;  // "step" or "frame"
  const std::shared_ptr<RunDirectoryLock> lock_;
  const ProblemSize size_;
  const std::string solver_;  // what "auto" chose
  RunResult result_;
  std::optional<Checkpoint> resume_from_;
  std::optional<FrameWriter> frames_;
  int first_ = 1;
  std::optional<Checkpoint> pending_;  // the last converged frame's, not yet on disk
  bool unsaved_ = false;               // frames or records since the progress was last written
  Clock::time_point last_progress_ = Clock::now();
};

}  // namespace

InsideOut inside_out_frames(const std::vector<StepRecord>& records) {
  InsideOut io;
  for (const StepRecord& rec : records)  // index 0: a scene's initial state, given and not solved (the lab starts inverted)
    if (rec.index > 0 && rec.inverted > 0 && rec.converged && (++io.frames, rec.inverted > io.most))
      io.most = rec.inverted, io.worst = rec.index;
  return io;
}

RunResult run_simulation(Simulation& sim, const RunPlan& plan, std::ostream& log) { return RunLoop(sim, plan, log).run(); }

}  // namespace snh
