#include "snh/io/usda.hpp"

#include <algorithm>
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
                double frames_per_second, double meters_per_unit, char up_axis) {
  if (!(meters_per_unit > 0.0) || !std::isfinite(meters_per_unit))
    throw std::invalid_argument(fmt::format("USD stage: metersPerUnit must be a positive number, got {}", meters_per_unit));
  if (up_axis != 'Y' && up_axis != 'Z') throw std::invalid_argument(fmt::format("USD stage: upAxis must be Y or Z, got '{}'", up_axis));
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
    if (!m.converged.empty() && m.converged.size() != m.frames.size())
      throw std::invalid_argument(fmt::format("USD mesh {}: {} convergence flags for {} frames", m.name, m.converged.size(), m.frames.size()));
    if (!m.normals.empty() && m.normals.size() != m.frames.size())
      throw std::invalid_argument(fmt::format("USD mesh {}: {} frames of normals for {} frames", m.name, m.normals.size(), m.frames.size()));
    for (const Eigen::Matrix3Xd& n : m.normals)
      if (n.cols() != m.frames[0].cols() || !n.allFinite())
        throw std::invalid_argument(fmt::format("USD mesh {}: normals of {} vertices (or not finite) for {} points", m.name, n.cols(),
                                                m.frames[0].cols()));
    if (m.uv.cols() > 0 && (m.uv.cols() != m.frames[0].cols() || !m.uv.allFinite()))
      throw std::invalid_argument(fmt::format("USD mesh {}: {} texture coordinates (or not finite) for {} points", m.name, m.uv.cols(),
                                              m.frames[0].cols()));
    if (m.triangles.size() > 0 && (m.triangles.minCoeff() < 0 || m.triangles.maxCoeff() >= m.frames[0].cols()))
      throw std::invalid_argument(fmt::format("USD mesh {}: a triangle index is out of range", m.name));
  }

  Out o;
  put(o, "#usda 1.0\n(\n    defaultPrim = \"{}\"\n    doc = \"written by snh\"\n    endTimeCode = {}\n    metersPerUnit = {:.17g}\n"
      "    framesPerSecond = {:.17g}\n    startTimeCode = 0\n    timeCodesPerSecond = {:.17g}\n    upAxis = \"{}\"\n)\n\n",
      root, frames ? frames - 1 : 0, meters_per_unit, frames_per_second, frames_per_second, up_axis);
  put(o, "def Xform \"{}\"\n{{\n", root);
  for (const UsdMesh& m : meshes) {
    put(o, "    def Mesh \"{}\"\n    {{\n", m.name);
    put(o, "        int[] faceVertexCounts = [");
    for (Eigen::Index f = 0; f < m.triangles.cols(); ++f) put(o, "{}3", f ? ", " : "");
    put(o, "]\n        int[] faceVertexIndices = [");
    for (Eigen::Index f = 0; f < m.triangles.cols(); ++f)
      put(o, "{}{}, {}, {}", f ? ", " : "", m.triangles(0, f), m.triangles(1, f), m.triangles(2, f));
    put(o, "]\n");
    // One 3-vector array per time code: "TYPE NAME.timeSamples = { 0: [...], 1: [...], ... }".
    const auto samples = [&o](const char* declaration, std::size_t count, const auto& array_at) {
      put(o, "        {}.timeSamples = {{\n", declaration);
      for (std::size_t f = 0; f < count; ++f) {
        put(o, "            {}: ", f);
        points(o, array_at(f));
        put(o, ",\n");
      }
      put(o, "        }}\n");
    };
    // The bounds of every frame (a tool frames and culls by them without reading the points).
    samples("float3[] extent", m.frames.size(), [&](std::size_t f) {
      Eigen::Matrix3Xd box = Eigen::Matrix3Xd::Zero(3, 2);
      if (m.frames[f].cols() > 0) box << m.frames[f].rowwise().minCoeff(), m.frames[f].rowwise().maxCoeff();
      return box;
    });
    if (!m.normals.empty()) {
      put(o, "        normal3f[] normals (\n            interpolation = \"vertex\"\n        )\n");
      samples("normal3f[] normals", m.normals.size(), [&](std::size_t f) -> const Eigen::Matrix3Xd& { return m.normals[f]; });
    }
    put(o, "        uniform token orientation = \"rightHanded\"\n");
    if (std::find(m.converged.begin(), m.converged.end(), false) != m.converged.end()) {
      put(o, "        custom bool snh:converged.timeSamples = {{\n");
      for (std::size_t f = 0; f < m.converged.size(); ++f) put(o, "            {}: {},\n", f, m.converged[f] ? "true" : "false");
      put(o, "        }}\n");
    }
    samples("point3f[] points", m.frames.size(), [&](std::size_t f) -> const Eigen::Matrix3Xd& { return m.frames[f]; });
    if (m.uv.cols() > 0) {
      put(o, "        texCoord2f[] primvars:st = [");
      for (Eigen::Index v = 0; v < m.uv.cols(); ++v) put(o, "{}({:.9g}, {:.9g})", v ? ", " : "", m.uv(0, v), m.uv(1, v));
      put(o, "] (\n            interpolation = \"vertex\"\n        )\n");
    }
    put(o, "        uniform token subdivisionScheme = \"none\"\n    }}\n");
  }
  put(o, "}}\n");
  write_atomically(path, [&](std::ostream& out) { out.write(o.data(), static_cast<std::streamsize>(o.size())); });
}

}  // namespace snh
