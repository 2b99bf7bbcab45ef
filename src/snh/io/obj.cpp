#include "snh/io/obj.hpp"

#include <fmt/format.h>
#include <fmt/os.h>

#include "snh/io/atomic_file.hpp"

namespace snh {

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles) {
  write_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer buf;
    for (Eigen::Index v = 0; v < positions.cols(); ++v)
      fmt::format_to(std::back_inserter(buf), "v {:.10g} {:.10g} {:.10g}\n", positions(0, v), positions(1, v), positions(2, v));
    for (Eigen::Index f = 0; f < triangles.cols(); ++f)
      fmt::format_to(std::back_inserter(buf), "f {} {} {}\n", triangles(0, f) + 1, triangles(1, f) + 1, triangles(2, f) + 1);
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  });
}

}  // namespace snh
