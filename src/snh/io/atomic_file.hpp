#pragma once
// Files appear whole or not at all (DESIGN.md): write to a temporary name beside the target, then rename.
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

/// Calls write(stream) on a temporary file next to path, then renames it to path.
/// Throws WriteError (naming path) if the file cannot be created, written or renamed; the temporary is removed.
void write_atomically(const std::filesystem::path& path, const std::function<void(std::ostream&)>& write);

/// Creates dir (and parents) if needed and checks that a file can be created in it.
/// Throws WriteError with a one-line reason otherwise.
void ensure_writable_directory(const std::filesystem::path& dir);

}  // namespace snh
