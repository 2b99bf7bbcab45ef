#pragma once
// Files appear whole or not at all (docs/design.md): write to a temporary name beside the target, then rename.
#include <filesystem>
#include <functional>
#include <ostream>
#include <stdexcept>
#include <string>

namespace snh {

/// An output file that could not be written; the message names the path and the reason.
class WriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An output path the program refuses to write to (bad input, not a failure to write): something there
/// that is not a regular file (a FIFO, a device, a socket, a directory), or a directory that holds
/// someone else's files. The message names the path and the reason.
class OutputRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws OutputRefused ("PATH: is a FIFO, not a regular file: refusing to replace it") if something
/// other than a regular file (or a symbolic link to one) is at path; nothing there, or a regular file, passes.
void check_replaceable(const std::filesystem::path& path);

/// Calls write(stream) on a temporary file next to path, then renames it to path.
/// Throws OutputRefused if path is not a regular file (check_replaceable), WriteError (naming path) if the
/// file cannot be created, written or renamed; the temporary is removed.
void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

/// Creates dir (and parents) if needed and checks that a file can be created in it.
/// Throws WriteError with a one-line reason otherwise.
void ensure_writable_directory(const std::filesystem::path& dir);

}  // namespace snh
