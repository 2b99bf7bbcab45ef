#pragma once
// The output directory of a run holds one run (docs/design.md): while a run writes there it holds an
// exclusive lock (a second run into the same directory is refused at once); a new run first removes the
// files a previous run of ours left (frames, stats, checkpoint, report), and nothing else; a resume checks
// that the frames it keeps are still there.
#include <filesystem>
#include <string>

namespace snh {

/// The lock on an output directory, held while this object lives (flock on DIR/.snh-lock: released by the
/// kernel when the process ends, however it ends). A directory the lock created and that holds nothing
/// but the lock file when the lock is released (a run refused or failed before its first file) is
/// removed, so that a failed start leaves nothing behind.
class RunDirectoryLock {
 public:
  /// Creates the directory if needed and takes the lock. Throws OutputRefused (one line: exit 2) if the
  /// directory is not empty and shows no run of ours (see holds_a_run_of_ours), unless `force`, or if
  /// another process holds the lock (naming its pid); WriteError (one line) if the directory cannot be used.
  explicit RunDirectoryLock(const std::filesystem::path& dir, bool force = false);
  ~RunDirectoryLock();
  RunDirectoryLock(const RunDirectoryLock&) = delete;
  RunDirectoryLock& operator=(const RunDirectoryLock&) = delete;
  /// True if the lock file was there before (an earlier run of ours used the directory).
  [[nodiscard]] bool found_earlier() const { return found_; }
  /// True if the directory was taken with `force` (its files with our names are replaced as ours).
  [[nodiscard]] bool forced() const { return forced_; }

 private:
  std::filesystem::path dir_;
  int fd_ = -1;
  bool found_ = false, forced_ = false, created_ = false;
};

/// True if dir shows a run of ours: the lock file .snh-lock, a checkpoint.bin, a frames.pvd, or a
/// stats.json or lab.json naming snh's version in its first 64 KiB (regular files only: never blocks).
bool holds_a_run_of_ours(const std::filesystem::path& dir);

/// Throws OutputRefused ("DIR: is not empty and holds no snh run (it has NAME): refusing to write a run
/// into it; ...") if dir exists, is not empty and does not hold a run of ours. `hint` ends the message
/// (how to override, where there is a way). A missing or empty directory passes.
void refuse_foreign_directory(const std::filesystem::path& dir, const std::string& hint);

/// Removes what a previous run of ours left in dir: NNN.obj and NNN.vtu frames, frames.pvd, stats.json,
/// stats.csv, checkpoint.bin, index.html, the report/ directory, a flesh run's surface/ and lbs/ directories
/// flesh.usda and bones.json, and temporaries of interrupted writes.
/// Other files stay. Files with those names in a directory that shows no run of ours (no lock file found
/// by `lock`, no checkpoint, no stats.json or lab.json naming snh's version), unless the lock was taken with
/// `force`, are someone else's: OutputRefused,
/// naming one, and nothing is removed. Returns the number of entries removed. Throws WriteError if one
/// cannot be removed.
int clear_previous_run(const std::filesystem::path& dir, const RunDirectoryLock& lock);

/// For a resume: frames 0 … last must be on disk (NNN.obj, and NNN.vtu when `vtu`). Throws
/// std::invalid_argument naming the first missing one.
void check_kept_frames(const std::filesystem::path& dir, int last, bool vtu);

}  // namespace snh
