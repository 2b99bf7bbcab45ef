#include "snh/io/usda.hpp"

#include <cctype>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"

namespace snh {
namespace {

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

using Out = fmt::memory_buffer;

template <class... A>
void put(Out& o, fmt::format_string<A...> f, A&&... a) {
  fmt::format_to(std::back_inserter(o), f, std::forward<A>(a)...);
}

void points(Out& o, const Eigen::Matrix3Xd& P) {
  o.push_back('[');
  for (Eigen::Index v = 0; v < P.cols(); ++v)
    fmt::format_to(std::back_inserter(o), "{}({:.9g}, {:.9g}, {:.9g})", v ? ", " : "", P(0, v), P(1, v), P(2, v));
  o.push_back(']');
}

}  // namespace

void write_usda(const std::filesystem::path& path, const std::string& root, const std::vector<UsdMesh>& meshes,
                double frames_per_second) {
  if (!is_identifier(root)) throw std::invalid_argument(fmt::format("USD prim name \"{}\" is not an identifier", root));
  if (!(frames_per_second > 0.0) || !std::isfinite(frames_per_second))
    throw std::invalid_argument(fmt::format("USD frames per second {} is not a positive number", frames_per_second));
  std::size_t frames = 0;
  for (const UsdMesh& m : meshes) {
    if (!is_identifier(m.name)) throw std::invalid_argument(fmt::format("USD prim name \"{}\" is not an identifier", m.name));
    if (m.frames.empty()) throw std::invalid_argument(fmt::format("USD mesh {} has no frames", m.name));
    frames = std::max(frames, m.frames.size());
    for (std::size_t f = 0; f < m.frames.size(); ++f) {
      if (m.frames[f].cols() != m.frames[0].cols())
        throw std::invalid_argument(fmt::format("USD mesh {}: frame {} has {} points, frame 0 {}", m.name, f,
                                                m.frames[f].cols(), m.frames[0].cols()));
      if (!m.frames[f].allFinite())
        throw std::invalid_argument(fmt::format("USD mesh {}: frame {} has a non-finite point", m.name, f));
    }
    if (m.triangles.size() > 0 && (m.triangles.minCoeff() < 0 || m.triangles.maxCoeff() >= m.frames[0].cols()))
      throw std::invalid_argument(fmt::format("USD mesh {}: a triangle index is out of range", m.name));
  }

  Out o;
  put(o, "#usda 1.0\n(\n    defaultPrim = \"{}\"\n    doc = \"written by snh\"\n    endTimeCode = {}\n    metersPerUnit = 1\n"
      "    framesPerSecond = {:.17g}\n    startTimeCode = 0\n    timeCodesPerSecond = {:.17g}\n    upAxis = \"Y\"\n)\n\n",
      root, frames ? frames - 1 : 0, frames_per_second, frames_per_second);
  put(o, "def Xform \"{}\"\n{{\n", root);
  for (const UsdMesh& m : meshes) {
    put(o, "    def Mesh \"{}\"\n    {{\n", m.name);
    put(o, "        int[] faceVertexCounts = [");
    for (Eigen::Index f = 0; f < m.triangles.cols(); ++f) put(o, "{}3", f ? ", " : "");
    put(o, "]\n        int[] faceVertexIndices = [");
    for (Eigen::Index f = 0; f < m.triangles.cols(); ++f)
      put(o, "{}{}, {}, {}", f ? ", " : "", m.triangles(0, f), m.triangles(1, f), m.triangles(2, f));
    put(o, "]\n        uniform token orientation = \"rightHanded\"\n");
    put(o, "        point3f[] points.timeSamples = {{\n");
    for (std::size_t f = 0; f < m.frames.size(); ++f) {
      put(o, "            {}: ", f);
      points(o, m.frames[f]);
      put(o, ",\n");
    }
    put(o, "        }}\n        uniform token subdivisionScheme = \"none\"\n    }}\n");
  }
  put(o, "}}\n");
  write_atomically(path, [&](std::ostream& out) { out.write(o.data(), static_cast<std::streamsize>(o.size())); });
}

}  // namespace snh
