#include "snh/run/run_directory.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <stdexcept>
#include <system_error>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"

namespace snh {
namespace fs = std::filesystem;

RunDirectoryLock::RunDirectoryLock(const fs::path& dir, bool force) : dir_(dir), forced_(force) {
  if (!force) refuse_foreign_directory(dir, "choose an empty or new output directory, or pass --force to write there anyway");
  std::error_code ec;
  created_ = !fs::exists(fs::symlink_status(dir, ec));
  ensure_writable_directory(dir);
  const fs::path path = dir / ".snh-lock";
  found_ = fs::exists(path, ec);
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw WriteError(fmt::format("cannot create {}: {}", path.string(), std::strerror(errno)));
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    if (err == ENOLCK || err == EINVAL || err == EOPNOTSUPP) return;  // a file system without locks: run unlocked
    char pid[32] = {};
    const ssize_t n = ::pread(fd_, pid, sizeof(pid) - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (err == EWOULDBLOCK)
      throw OutputRefused(fmt::format("another snh run is writing to {}{}: wait for it to finish or choose another output "
                                   "directory",
                                   dir.string(), n > 0 ? fmt::format(" (process {})", std::string(pid, std::strcspn(pid, "\n"))) : ""));
    throw WriteError(fmt::format("cannot lock {}: {}", path.string(), std::strerror(err)));
  }
  const std::string me = fmt::format("{}\n", ::getpid());
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, me.data(), me.size(), 0) != static_cast<ssize_t>(me.size())) {
    // The pid is only for the message of a second run; the lock itself holds.
  }
}

RunDirectoryLock::~RunDirectoryLock() {
  // A directory this lock created that holds only the lock file: the run never wrote anything, so nothing
  // is left (removed while the lock is held; a second run refused meanwhile never waits for it).
  if (created_ && fd_ >= 0) {
    std::error_code ec;
    bool only_lock = true;
    for (const fs::directory_entry& e : fs::directory_iterator(dir_, ec))
      if (e.path().filename() != ".snh-lock") only_lock = false;
    if (!ec && only_lock) {
      fs::remove(dir_ / ".snh-lock", ec);
      fs::remove(dir_, ec);
    }
  }
  if (fd_ >= 0) ::close(fd_);  // releases the lock; the file stays (removing it would race a waiting run)
}

bool holds_a_run_of_ours(const fs::path& dir) {
  std::error_code ec;
  for (const char* f : {".snh-lock", "checkpoint.bin", "frames.pvd"})
    if (fs::is_regular_file(dir / f, ec)) return true;
  for (const char* f : {"stats.json", "lab.json"}) {
    if (!fs::is_regular_file(dir / f, ec)) continue;  // a FIFO or a device there would block or never end
    std::ifstream in(dir / f, std::ios::binary);
    std::string head(64 * 1024, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    if (head.find("\"snh_version\"") != std::string::npos) return true;
  }
  return false;
}

void refuse_foreign_directory(const fs::path& dir, const std::string& hint) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return;  // missing (created later), or not a directory (refused later)
  std::string first;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (first.empty() || name < first) first = name;
  }
  if (first.empty() || holds_a_run_of_ours(dir)) return;
  throw OutputRefused(fmt::format("{}: is not empty and holds no snh run (it has {}): refusing to write a run into it; {}",
                                  dir.string(), first, hint));
}

namespace {

/// The files of ours in `dir` whose names `ours` matches (regular files, or links to one), and in the
/// subdirectories `subdirs` names, theirs by the same rule, recursively; appended to `doomed`, each directory
/// after its contents to `dirs` (removed only if nothing else is left in it). Something else under one of
/// our names (a FIFO, a device, a directory) is not ours: appended to `foreign`.
void files_of_ours(const fs::path& dir, const std::regex& ours,
                   const std::vector<std::pair<std::string, const std::regex*>>& subdirs, std::vector<fs::path>& doomed,
                   std::vector<fs::path>& dirs, std::vector<fs::path>& foreign, std::error_code& ec) {
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const bool directory = e.is_directory(ec) && !e.is_symlink(ec);
    if (directory) {
      for (const auto& [sub, rule] : subdirs)
        if (name == sub) {
          files_of_ours(e.path(), *rule, sub == "report" ? std::vector<std::pair<std::string, const std::regex*>>{{"frames", rule}}
                                                         : std::vector<std::pair<std::string, const std::regex*>>{},
                        doomed, dirs, foreign, ec);
          dirs.push_back(e.path());
        }
    }
    if (std::regex_match(name, ours)) (e.is_regular_file(ec) ? doomed : foreign).push_back(e.path());
  }
}

}  // namespace

int clear_previous_run(const fs::path& dir, const RunDirectoryLock& lock) {
  static const std::regex ours(R"((?:(?:failed_)?\d{3,}\.(?:obj|vtu)|frames\.pvd|stats\.json|stats\.csv|checkpoint\.bin|index\.html|flesh\.usda|bones\.json|muscles\.json))"
                               R"((?:\.tmp\.\d+)?|\.snh-write-test\.\d+)");
  // Inside surface/ and lbs/ only NNN.obj (or failed_NNN.obj); inside report/ (and report/frames/) only its scripts.
  static const std::regex frames(R"((?:failed_)?\d{3,}\.obj(?:\.tmp\.\d+)?)");
  static const std::regex report(R"((?:data|snh-report|\d{3,})\.js(?:\.tmp\.\d+)?)");
  std::vector<fs::path> doomed, dirs, foreign;
  std::error_code ec;
  files_of_ours(dir, ours, {{"surface", &frames}, {"lbs", &frames}, {"report", &report}}, doomed, dirs, foreign, ec);
  if (ec) throw WriteError(fmt::format("cannot list {}: {}", dir.string(), ec.message()));
  // Files with our names in a directory that shows no run of ours are someone else's: refuse to replace them.
  if (!doomed.empty() && !lock.found_earlier() && !lock.forced() && !holds_a_run_of_ours(dir))
    throw OutputRefused(fmt::format("{} holds {} but no snh run: an snh run would replace it; choose an empty or new output "
                                 "directory",
                                 dir.string(), doomed.front().filename().string()));
  // Something not a regular file where the run will write (a FIFO named flesh.usda, a directory named
  // lbs/003.obj) is refused now, before anything is removed or computed, as the run's writers would refuse it.
  for (const fs::path& p : foreign) check_replaceable(p);
  for (const fs::path& p : doomed) {
    fs::remove(p, ec);
    if (ec) throw WriteError(fmt::format("cannot remove {} (left by an earlier run): {}", p.string(), ec.message()));
  }
  for (const fs::path& d : dirs)  // deepest first; a directory that holds anything of someone else's stays
    if (fs::is_empty(d, ec)) fs::remove(d, ec);
  return static_cast<int>(doomed.size());
}

void check_kept_frames(const fs::path& dir, int last, bool vtu) {
  for (int i = 0; i <= last; ++i)
    for (const char* ext : {"obj", "vtu"}) {
      if (std::string(ext) == "vtu" && !vtu) continue;
      const fs::path f = dir / fmt::format("{:03d}.{}", i, ext);
      std::error_code ec;
      if (!fs::is_regular_file(f, ec))
        throw std::invalid_argument(fmt::format("cannot resume: {} is missing (the run being resumed wrote frames 000 to "
                                                "{:03d}); start the run again without --resume",
                                                f.string(), last));
    }
}

}  // namespace snh
