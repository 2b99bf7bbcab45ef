#pragma once
// Opening an input file (docs/design.md): every reader (meshes, surfaces, scenes, checkpoints) checks what
// is at the path before it reads, so that a directory, a FIFO, a device such as /dev/zero or a file too
// large to be one of ours fails at once with one line naming the file, instead of blocking, growing
// without bound or failing deep inside a library.
#include <cstdint>
#include <filesystem>
#include <string>

namespace snh {

/// The largest input file read (1 GiB): text meshes of about ten million cells.
constexpr std::uintmax_t max_input_bytes = std::uintmax_t{1} << 30;

/// What is wrong with reading `path` as a `what` (e.g. "mesh file"), as a one-line message naming the
/// path — "PATH: cannot open the mesh file" (missing), "PATH: is a directory, not a mesh file", "PATH: is not
/// a regular file (a FIFO): cannot read a mesh file from it", "PATH: is too large for a mesh file (N bytes;
/// input files are at most 1073741824 bytes, 1 GiB)" —
/// or "" when it is a regular file (or a symbolic link to one) of at most max_input_bytes.
/// `size`, when given, receives the file's size.
std::string input_file_problem(const std::filesystem::path& path, const std::string& what, std::uintmax_t* size = nullptr);

/// The first `limit` bytes of the regular file at path (fewer if it is shorter); "" if it cannot be read.
std::string read_head(const std::filesystem::path& path, std::size_t limit);

}  // namespace snh
