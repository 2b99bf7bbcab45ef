#include "snh/io/obj.hpp"

#include <charconv>
#include <string>

#include <fmt/format.h>
#include <fmt/os.h>

#include "snh/io/atomic_file.hpp"

namespace snh {

std::string obj_faces(const Eigen::Matrix3Xi& triangles) {
  fmt::memory_buffer buf;
  for (Eigen::Index f = 0; f < triangles.cols(); ++f)
    fmt::format_to(std::back_inserter(buf), "f {} {} {}\n", triangles(0, f) + 1, triangles(1, f) + 1, triangles(2, f) + 1);
  return fmt::to_string(buf);
}

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, std::string_view faces) {
  write_atomically(path, [&](std::ostream& out) {
    // "v %.10g %.10g %.10g" per vertex by std::to_chars (the same characters as printf's, which fmt's
    // "{:.10g}" also gives: tested), without fmt's per-call formatting overhead on every coordinate.
    std::string buf;
    buf.reserve(static_cast<std::size_t>(positions.cols()) * 48);
    char line[3 * 32 + 4];
    for (Eigen::Index v = 0; v < positions.cols(); ++v) {
      char* p = line;
      *p++ = 'v';
      for (int d = 0; d < 3; ++d) {
        *p++ = ' ';
        p = std::to_chars(p, line + sizeof line, positions(d, v), std::chars_format::general, 10).ptr;
      }
      *p++ = '\n';
      buf.append(line, p);
    }
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    out.write(faces.data(), static_cast<std::streamsize>(faces.size()));
  });
}

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles) {
  write_obj(path, positions, obj_faces(triangles));
}

}  // namespace snh
