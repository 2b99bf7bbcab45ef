#include "snh/io/atomic_file.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

#include <fmt/format.h>
#include <unistd.h>

namespace snh {

namespace {

/// What a file that is not a regular one is, for messages.
const char* kind_of(std::filesystem::file_type t) {
  using std::filesystem::file_type;
  switch (t) {
    case file_type::directory: return "a directory";
    case file_type::fifo: return "a FIFO";
    case file_type::socket: return "a socket";
    case file_type::block: return "a block device";
    case file_type::character: return "a character device";
    default: return "not a regular file";
  }
}

}  // namespace

void check_replaceable(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);  // through a symbolic link
  if (!std::filesystem::exists(st) || std::filesystem::is_regular_file(st)) return;
  const std::string kind = kind_of(st.type());
  throw OutputRefused(fmt::format("{}: is {}{}: refusing to replace it", path.string(),
                                  kind == "not a regular file" ? "" : kind + ", ", "not a regular file"));
}

void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write) {
  check_replaceable(path);
  const std::filesystem::path tmp = path.string() + fmt::format(".tmp.{}", ::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw WriteError(fmt::format("cannot create {}: {}", tmp.string(), std::strerror(errno)));
    write(out);
    out.flush();
    if (!out) {
      const std::string reason = std::strerror(errno);
      out.close();
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      throw WriteError(fmt::format("cannot write {}: {}", path.string(), reason));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw WriteError(fmt::format("cannot rename {} to {}: {}", tmp.string(), path.string(), ec.message()));
  }
}

void ensure_writable_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw OutputRefused(fmt::format("output directory {} exists and is not a directory", dir.string()));
  std::filesystem::create_directories(dir, ec);
  if (ec) throw WriteError(fmt::format("cannot create output directory {}: {}", dir.string(), ec.message()));
  const std::filesystem::path probe = dir / fmt::format(".snh-write-test.{}", ::getpid());
  {
    std::ofstream out(probe);
    if (!out) throw WriteError(fmt::format("output directory {} is not writable: {}", dir.string(), std::strerror(errno)));
  }
  std::filesystem::remove(probe, ec);
}

}  // namespace snh
