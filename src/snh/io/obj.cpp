#include "snh/io/obj.hpp"

#include <charconv>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <fmt/os.h>

#include "snh/io/atomic_file.hpp"

namespace snh {

std::string obj_faces(const Eigen::Matrix3Xi& triangles, bool texcoords, bool normals) {
  // A corner names its vertex, and its texture coordinate and normal by the same index: "i", "i/i", "i//i", "i/i/i".
  const char* corner = texcoords && normals ? " {0}/{0}/{0}" : texcoords ? " {0}/{0}" : normals ? " {0}//{0}" : " {0}";
  fmt::memory_buffer buf;
  for (Eigen::Index f = 0; f < triangles.cols(); ++f) {
    buf.push_back('f');
    for (int c = 0; c < 3; ++c) fmt::format_to(std::back_inserter(buf), fmt::runtime(corner), triangles(c, f) + 1);
    buf.push_back('\n');
  }
  return fmt::to_string(buf);
}

namespace {
/// "TAG x y …" per column with `digits` significant digits, by std::to_chars (the same characters as printf's
/// "%.10g", which fmt's "{:.10g}" also gives: tested), without fmt's per-call overhead on every coordinate.
template <int Rows>
void append_rows(std::string& buf, std::string_view tag, const Eigen::Matrix<double, Rows, Eigen::Dynamic>& m, int digits) {
  buf.reserve(buf.size() + static_cast<std::size_t>(m.cols()) * (16 * Rows + 4));
  char line[Rows * 32 + 8];
  for (Eigen::Index v = 0; v < m.cols(); ++v) {
    char* p = line;
    for (const char c : tag) *p++ = c;
    for (int d = 0; d < Rows; ++d) {
      *p++ = ' ';
      p = std::to_chars(p, line + sizeof line, m(d, v), std::chars_format::general, digits).ptr;
    }
    *p++ = '\n';
    buf.append(line, p);
  }
}
}  // namespace

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, std::string_view faces) {
  write_atomically(path, [&](std::ostream& out) {
    std::string buf;
    append_rows<3>(buf, "v", positions, 10);
    out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
    out.write(faces.data(), static_cast<std::streamsize>(faces.size()));
  });
}

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix2Xd& texcoords,
               const Eigen::Matrix3Xd& normals, const Eigen::Matrix3Xi& triangles) {
  const bool st = texcoords.cols() > 0, vn = normals.cols() > 0;
  if ((st && texcoords.cols() != positions.cols()) || (vn && normals.cols() != positions.cols()))
    throw std::invalid_argument(fmt::format("{}: {} vertices with {} texture coordinates and {} normals", path.string(),
                                            positions.cols(), texcoords.cols(), normals.cols()));
  std::string buf;
  append_rows<3>(buf, "v", positions, 10);
  if (st) append_rows<2>(buf, "vt", texcoords, 8);
  if (vn) append_rows<3>(buf, "vn", normals, 7);
  buf += obj_faces(triangles, st, vn);
  write_atomically(path, [&](std::ostream& out) { out.write(buf.data(), static_cast<std::streamsize>(buf.size())); });
}

void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles) {
  write_obj(path, positions, obj_faces(triangles));
}

}  // namespace snh
