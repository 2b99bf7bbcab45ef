#include "snh/rig/model_build.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <map>
#include <system_error>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "snh/rig/skinning.hpp"

namespace snh::rig_build {

namespace fs = std::filesystem;

/// Text from a file or a library on one line: its lines joined by "; ", other control characters as spaces.
std::string one_line(std::string_view text) {
  std::string out, line;
  const auto flush = [&] {
    const auto first = line.find_first_not_of(' '), last = line.find_last_not_of(' ');
    if (first != std::string::npos) {
      if (!out.empty()) out += "; ";
      out += line.substr(first, last - first + 1);
    }
    line.clear();
  };
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '\n' || ch == '\r') flush();
    else line += (c < 0x20 || c == 0x7f) ? ' ' : ch;
  }
  flush();
  return out;
}

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw RigError(fmt::format("{}: {}", one_line(path.string()), what));
}

std::uintmax_t check_file(const fs::path& path, std::string_view kind) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) fail(path, ec && ec != std::errc::no_such_file_or_directory ? fmt::format("cannot open ({})", ec.message())
                                                                                    : std::string("no such file"));
  if (fs::is_directory(st)) fail(path, fmt::format("a directory, not a {} file", kind));
  if (!fs::is_regular_file(st)) fail(path, "not a regular file");
  const std::uintmax_t n = fs::file_size(path, ec);
  if (ec) fail(path, fmt::format("cannot read its size ({})", ec.message()));
  if (n == 0) fail(path, fmt::format("an empty file, not a {} file", kind));
  if (n > max_file_bytes) fail(path, fmt::format("too large for a {} file ({} bytes; at most {})", kind, n, max_file_bytes));
  return n;
}

void SkinData::store(RiggedModel& out) const {
  const auto cols = [](std::size_t n) { return static_cast<Eigen::Index>(n); };
  out.vertices.resize(3, cols(xyz.size()));
  out.joint_index.resize(4, cols(xyz.size()));
  out.joint_weight.resize(4, cols(xyz.size()));
  for (std::size_t v = 0; v < xyz.size(); ++v) {
    out.vertices.col(cols(v)) = xyz[v];
    out.joint_index.col(cols(v)) = jidx[v];
    out.joint_weight.col(cols(v)) = jw[v];
  }
  out.triangles.resize(3, cols(tri.size()));
  for (std::size_t t = 0; t < tri.size(); ++t) out.triangles.col(cols(t)) = tri[t];
  out.uv.resize(2, 0);
  if (all_uv && uv.size() == xyz.size()) {
    out.uv.resize(2, cols(uv.size()));
    for (std::size_t v = 0; v < uv.size(); ++v) out.uv.col(cols(v)) = uv[v];
  }
  out.normals.resize(3, 0);
  if (all_normals && normal.size() == xyz.size()) {
    out.normals.resize(3, cols(normal.size()));
    for (std::size_t v = 0; v < normal.size(); ++v) {
      const double len = normal[v].norm();
      out.normals.col(cols(v)) = len > 0.0 ? Eigen::Vector3d(normal[v] / len) : Eigen::Vector3d::Zero();
    }
  }
}

/// A node's transform when the spec's TRS is not enough: translation · rotation · scale from a 4 by 4 matrix.
/// Returns an empty string and sets `out`, or the reason it cannot be decomposed.
std::string decompose(const Eigen::Matrix4d& m, Transform& out) {
  if (!m.allFinite()) return "has a value that is not finite";
  if ((m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) return "is not affine (last row not 0 0 0 1)";
  const Eigen::Matrix3d a = m.topLeftCorner<3, 3>();
  const Eigen::Vector3d s = a.colwise().norm().transpose();
  if (!(s.minCoeff() > 1e-12 * std::max(1.0, s.maxCoeff()))) return "has a zero scale";
  const Eigen::Matrix3d r = a * s.cwiseInverse().asDiagonal();
  if (r.determinant() < 0) return "mirrors (a negative scale)";
  // Columns orthogonal up to float32 storage (about 1e-7) and the products of a few of them.
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-4) return "shears (not translation, rotation, scale)";
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  out.translation = m.block<3, 1>(0, 3);
  out.rotation = Eigen::Quaterniond(Eigen::Matrix3d(svd.matrixU() * svd.matrixV().transpose())).normalized();
  out.scale = s;
  return {};
}

/// Vertices at the same position (bitwise, +0 and −0 alike) merged, in order of first appearance; triangles
/// that lose a corner to the merge dropped from the welded surface.
void weld(RiggedModel& out) {
  std::map<std::array<std::uint64_t, 3>, int> index;
  const Eigen::Index n = out.vertices.cols();
  out.weld.assign(static_cast<std::size_t>(n), -1);
  std::vector<Eigen::Index> first;
  for (Eigen::Index v = 0; v < n; ++v) {
    std::array<std::uint64_t, 3> key;
    for (int c = 0; c < 3; ++c) key[static_cast<std::size_t>(c)] = std::bit_cast<std::uint64_t>(out.vertices(c, v) + 0.0);
    const auto [it, added] = index.try_emplace(key, static_cast<int>(first.size()));
    if (added) first.push_back(v);
    out.weld[static_cast<std::size_t>(v)] = it->second;
  }
  out.surface_vertices.resize(3, static_cast<Eigen::Index>(first.size()));
  for (std::size_t s = 0; s < first.size(); ++s) out.surface_vertices.col(static_cast<Eigen::Index>(s)) = out.vertices.col(first[s]);
  std::vector<Eigen::Vector3i> kept;
  for (Eigen::Index t = 0; t < out.triangles.cols(); ++t) {
    Eigen::Vector3i w;
    for (int c = 0; c < 3; ++c) w(c) = out.weld[static_cast<std::size_t>(out.triangles(c, t))];
    if (w(0) != w(1) && w(1) != w(2) && w(0) != w(2)) kept.push_back(w);
  }
  out.surface_triangles.resize(3, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t t = 0; t < kept.size(); ++t) out.surface_triangles.col(static_cast<Eigen::Index>(t)) = kept[t];
}


/// A channel of a joint below non-joint nodes whose transforms B were folded into its rest transform: its
/// keys made relative to the joint's parent (or the model) too. For B a similarity (uniform scale s, rotation
/// R, translation b): translation t → b + s·R·t, rotation q → R·q, scale σ → s·σ; these maps are affine, so
/// they commute with every interpolation (tangents take the linear part only).
void fold_in(const fs::path& path, const Eigen::Matrix4d& between, Channel& c, const std::string& joint) {
  Transform b;
  const std::string what = fmt::format("joint \"{}\" is animated below nodes whose transforms", one_line(joint));
  if (const std::string why = decompose(between, b); !why.empty()) fail(path, fmt::format("{}: the product {}", what, why));
  const double s = b.scale.mean();
  if ((b.scale.array() - s).abs().maxCoeff() > 1e-6 * s)
    fail(path, fmt::format("{} scale non-uniformly ({} {} {}): not supported", what, b.scale(0), b.scale(1), b.scale(2)));
  const bool cubic = c.interpolation == Interpolation::cubic_spline;
  for (Eigen::Index k = 0; k < c.values.cols(); ++k) {
    const bool tangent = cubic && k % 3 != 1;
    // Element by element: GCC 12 wrongly warns of AVX-512 loads past a fixed-size vector copied from or to a
    // dynamic-size column.
    Eigen::Vector4d v = Eigen::Vector4d::Zero();
    for (Eigen::Index r = 0; r < c.values.rows(); ++r) v(r) = c.values(r, k);
    switch (c.path) {
      case ChannelPath::translation:
        v.head<3>() = s * (b.rotation * Eigen::Vector3d(v.head<3>()));
        if (!tangent) v.head<3>() += b.translation;
        break;
      case ChannelPath::rotation: v = (b.rotation * Eigen::Quaterniond(v(3), v(0), v(1), v(2))).coeffs(); break;
      case ChannelPath::scale: v *= s; break;
    }
    for (Eigen::Index r = 0; r < c.values.rows(); ++r) c.values(r, k) = v(r);
  }
}


/// Finite values can still overflow when composed: the rest pose and its skinning matrices must be finite.
void check_rest(const RiggedModel& out) {
  std::vector<Eigen::Affine3d> world;
  try {
    world = out.skeleton.world(out.skeleton.rest_pose());
  } catch (const std::invalid_argument& e) {
    fail(out.source, fmt::format("at rest, {}", one_line(e.what())));
  }
  for (std::size_t j = 0; j < world.size(); ++j)
    if (!(world[j].matrix() * out.inverse_bind[j]).allFinite())
      fail(out.source, fmt::format("joint \"{}\": its rest transform times its inverse bind matrix is not finite",
                       one_line(out.skeleton.joints[j].name)));
  try {
    (void)skin_vertices(out, world);
  } catch (const std::invalid_argument& e) {
    fail(out.source, fmt::format("at rest, {}", one_line(e.what())));
  }
}


}  // namespace snh::rig_build
