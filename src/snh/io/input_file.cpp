#include "snh/io/input_file.hpp"

#include <fstream>
#include <system_error>

#include <fmt/format.h>

namespace snh {
namespace fs = std::filesystem;

std::string input_file_problem(const fs::path& path, const std::string& what, std::uintmax_t* size) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);  // through a symbolic link
  const std::string p = path.string();
  if (!fs::exists(st)) {
    if (ec && ec != std::errc::no_such_file_or_directory) return fmt::format("{}: cannot open the {}: {}", p, what, ec.message());
    return fmt::format("{}: cannot open the {}", p, what);
  }
  if (fs::is_directory(st)) return fmt::format("{}: is a directory, not a {}", p, what);
  if (!fs::is_regular_file(st)) {
    const char* kind = fs::is_fifo(st) ? " (a FIFO)" : fs::is_character_file(st) ? " (a character device)"
                       : fs::is_block_file(st) ? " (a block device)" : fs::is_socket(st) ? " (a socket)" : "";
    return fmt::format("{}: is not a regular file{}: cannot read a {} from it", p, kind, what);
  }
  const std::uintmax_t n = fs::file_size(path, ec);
  if (ec) return fmt::format("{}: cannot read the size of the {}: {}", p, what, ec.message());
  if (n > max_input_bytes)
    return fmt::format("{}: is too large for a {} ({} bytes; input files are at most {} bytes, 1 GiB)", p, what, n, max_input_bytes);
  if (size) *size = n;
  return "";
}

std::string read_head(const fs::path& path, std::size_t limit) {
  std::ifstream in(path, std::ios::binary);
  std::string head(limit, '\0');
  in.read(head.data(), static_cast<std::streamsize>(limit));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

}  // namespace snh
