#include "snh/io/obj.hpp"

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
    fmt::memory_buffer buf;
    for (Eigen::Index v = 0; v < positions.cols(); ++v)
      fmt::format_to(std::back_inserter(buf), "v {:.10g} {:.10g} {:.10g}\n", positions(0, v), positions(1, v), positions(2, v));
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    out.write(faces.data(), static_cast<std::streamsize>(faces.size()));
  });
}

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles) {
  write_obj(path, positions, obj_faces(triangles));
}

}  // namespace snh
