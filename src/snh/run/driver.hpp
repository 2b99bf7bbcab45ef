#pragma once
// The one loop that runs a Simulation frame by frame and keeps its output directory trustworthy
// (docs/design.md): it locks the directory, clears a previous run's files (or, for --resume, checks the
// checkpoint, the kept frames and the history), writes stats.json with status "running" before any work,
// then every frame (NNN.obj, NNN.vtu) and its stats record; the progress (frames.pvd, the stats so far and
// the last converged frame's checkpoint) after the first completed frame, then at most every
// progress_interval seconds and at the end, with the final stats' status "finished", "stopped" (a frame
// failed) or "interrupted" (a signal), or "running" when an exception ends the run. A run killed without
// warning leaves status "running": unfinished, its last progress_interval of frames not in the stats. What
// differs between the stretch test and a scene (the records' table, the log lines, the record's own
// fields, run-level results) comes in through the RunPlan.
#include <filesystem>
#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "snh/run/run_directory.hpp"
#include "snh/sim/simulation.hpp"
#include "snh/run/stats.hpp"

namespace snh {

/// How a run ended, as every kind of run reports it (RunResult; a scene's and the stretch test's results).
struct RunOutcome {
  bool all_converged = true;
  std::string failure;     ///< why the run stopped early, or its first frame that did not converge (empty when all did)
  std::vector<int> unconverged;  ///< the frames that did not converge (with keep_going, the run went on past them)
  std::string failed_frame;      ///< the frame file where the run stopped without converging (failed_NNN.obj), or empty
  int interrupted_by = 0;  ///< the signal (SIGINT, SIGTERM) that stopped the run; 0 if none
  double total_seconds = 0.0;
  double peak_memory_mib = 0.0;  ///< peak resident memory of the process (VmHWM)
  /// What makes the results doubtful though the frames converged, one sentence each without the "warning: " the
  /// log puts before it: the plan's (known before the first frame), then the frames that converged with elements
  /// turned inside out (inside_out_frames). Empty for a clean run; stats.json's "warnings".
  std::vector<std::string> warnings;
};

struct RunResult : RunOutcome {
  std::vector<StepRecord> records;  ///< with the initial state's first where the table has one
};

/// The converged frames (steps) of `records` that hold inverted elements: how many, and the most in one of them
/// (`worst`, the first with that many). A scene's initial state (frame 0) is given, not solved, and not counted.
struct InsideOut {
  int frames = 0, most = 0, worst = 0;
};
[[nodiscard]] InsideOut inside_out_frames(const std::vector<StepRecord>& records);

struct RunPlan {
  std::filesystem::path out;
  /// The lock on `out` when the caller holds it beyond the run (to write the report before another run
  /// may start there); null: the run takes it and releases it when it returns.
  std::shared_ptr<RunDirectoryLock> lock;
  const RecordTable* table = nullptr;
  int frames = 1;                 ///< frames (steps) after the initial state
  double frame_duration = 1.0;    ///< frame i ends at time i · frame_duration
  int substeps = 1;               ///< solves per frame, at (i − 1) · frame_duration + k · substep
  double substep = 1.0;
  bool write_vtu = true;
  /// Seconds between two writes of the progress (frames.pvd, stats.json, stats.csv, checkpoint.bin) while
  /// the run goes on: a run killed outright loses at most that much; 0: after every frame.
  double progress_interval = 1.0;
  bool resume = false;            ///< continue from DIR/checkpoint.bin
  /// A frame that does not converge is written and recorded as such (its record's `converged` false, its
  /// progress line NOT CONVERGED, stats.json's `unconverged_frames`), and the run goes on from its state
  /// instead of stopping there; the run still reports that not all frames converged.
  bool keep_going = false;
  std::string fingerprint;        ///< the settings that decide the result (a resume must match)
  nlohmann::json settings;        ///< stats.json's fields that describe the run
  /// What the run's set-up makes doubtful, known before its first frame (a flesh's bones that press flesh inside
  /// out or bind nothing, a mesh's cells re-oriented): the header prints each, and the outcome starts with them.
  std::vector<std::string> warnings;
  bool live_progress = false;     ///< the log is a terminal: a line updated at every Newton iteration
  /// Called before the first frame, after the directory is locked and checked: the run's header lines.
  std::function<void(std::ostream&)> header;
  /// Fills the table's own fields of a record (energies) from the state reached; `report` is null for
  /// the initial state.
  std::function<void(StepRecord&, const StepReport* report)> fill;
  /// Writes a frame's own files besides NNN.obj and NNN.vtu (a flesh run's render surfaces), from the state
  /// reached, their names prefixed by `prefix` (kFailedPrefix for the frame where a run stopped without
  /// converging, else empty); a WriteError is reported as the frame's.
  std::function<void(int index, double time, const Eigen::VectorXd& x, const std::string& prefix)> write_frame;
  /// The log line of a completed frame (without newline).
  std::function<std::string(const StepRecord&)> line;
  /// The live progress text at a Newton iteration.
  std::function<std::string(int frame, int substep, int iteration, double residual)> live;
  /// A failed frame's failure text from its report (default: the report's own).
  std::function<std::string(const StepReport&)> failure;
  /// Run-level results added to the final stats.json (the stretch test's middle width), and files made from
  /// the frames at the end (a flesh run's caches); `result` holds every frame's record, a resumed run's too.
  std::function<void(const RunResult& result, nlohmann::json& stats)> finish;
  /// The last line (without newline).
  std::function<std::string(const RunResult&)> summary;
};

/// Runs the plan: see the header. Throws MemoryEstimateError before any work when the run's memory estimate
/// (memory_estimate.hpp) exceeds this process' limits, OutOfMemoryError (one line: the estimate, what is
/// kept, what needs less; stats.json says "stopped") when a frame runs out of memory. Throws WriteError (naming the frame and what is kept) when a file
/// cannot be written, std::invalid_argument when a resume is not possible (before any work).
[[nodiscard]] RunResult run_simulation(Simulation& sim, const RunPlan& plan, std::ostream& log);

}  // namespace snh
