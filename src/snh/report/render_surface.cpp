// A flesh run's render surface in its report (report_data.hpp): the skins of every frame, the flesh's
// distance from the skinned surface, the normal groups and the bones.
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/contact/surface_distance.hpp"
#include "snh/report/report.hpp"
#include "snh/report/report_data.hpp"

namespace snh::report_internal {

RenderSurface::RenderSurface(const fs::path& dir, std::size_t frame_count, double mm_per_unit) : dir_(dir), mm_per_unit_(mm_per_unit) {
  const SurfaceMesh first = read(dir / "surface" / "000.obj");
  triangles_ = first.triangles;
  vertex_count_ = first.vertices.cols();
  group_normals(first);
  if (fs::exists(dir / "bones.json")) read_bones(dir / "bones.json", frame_count);
}

json RenderSurface::frame(std::size_t i, const std::string& vtu) {
  const std::string name = fs::path(vtu).stem().string() + ".obj";
  json out;
  SurfaceMesh shape[2];
  for (int k = 0; k < 2; ++k) {
    const char* part = k == 0 ? "surface" : "lbs";
    const fs::path path = dir_ / part / name;
    if (!fs::exists(path))
      throw ReportError(fmt::format("{}: missing: a flesh run writes one per frame, and frame {} ({}) has none",
                                    path.string(), i, vtu));
    SurfaceMesh& s = shape[k] = read(path);
    if (s.vertices.cols() != vertex_count_ || s.triangles.cols() != triangles_.cols())
      throw ReportError(fmt::format("{}: {} vertices and {} triangles, but surface/000.obj has {} and {}", path.string(),
                                    s.vertices.cols(), s.triangles.cols(), vertex_count_, triangles_.cols()));
    if (s.triangles != triangles_)
      throw ReportError(fmt::format("{}: its triangles are not those of surface/000.obj", path.string()));
    std::vector<float> xyz(3 * vertex_count_);
    for (Eigen::Index v = 0; v < vertex_count_; ++v)
      for (int a = 0; a < 3; ++a) {
        xyz[3 * v + a] = static_cast<float>(s.vertices(a, v));
        bounds_[a].add(s.vertices(a, v));
      }
    out[k == 0 ? "flesh" : "lbs"] = encode(xyz);
  }
  // Each flesh vertex's signed distance from the skinned surface; its own skinned position bounds the search.
  std::vector<float> distance(static_cast<std::size_t>(vertex_count_));
  Range frame_range;
  try {
    const contact::SurfaceDistance lbs(shape[1].vertices, triangles_);
    for (Eigen::Index v = 0; v < vertex_count_; ++v) {
      const double d = mm_per_unit_ * lbs.signed_distance(shape[0].vertices.col(v), v);
      distance[static_cast<std::size_t>(v)] = static_cast<float>(d);
      frame_range.add(d);
      distance_range_.add(d);
    }
  } catch (const std::invalid_argument& e) {
    throw ReportError(fmt::format("{}: {}", (dir_ / "lbs" / name).string(), e.what()));
  }
  out["distance"] = encode(distance);
  outside_.push_back(frame_range.hi >= frame_range.lo ? json(std::max(0.0, frame_range.hi)) : json(nullptr));
  inside_.push_back(frame_range.hi >= frame_range.lo ? json(std::max(0.0, -frame_range.lo)) : json(nullptr));
  if (has_bones_) {
    std::vector<float> segments(bones_[i].begin(), bones_[i].end());
    for (std::size_t k = 0; k < segments.size(); ++k) bounds_[k % 3].add(bones_[i][k]);
    out["bones"] = encode(segments);
  }
  return out;
}

json RenderSurface::summary() const {
  std::vector<std::uint32_t> tri(triangles_.data(), triangles_.data() + triangles_.size());
  json lo = json::array(), hi = json::array();
  for (const Range& r : bounds_) {
    const json lh = r.to_json(0.0);
    lo.push_back(lh[0]);
    hi.push_back(lh[1]);
  }
  return {{"vertex_count", vertex_count_},
          {"triangle_count", triangles_.cols()},
          {"triangles", encode(tri)},
          {"bones", has_bones_ ? json(bone_names_) : json(nullptr)},
          {"bounds", {{"min", lo}, {"max", hi}}},
          {"normal_groups", encode(groups_)},
          {"distance", {{"label", "distance from the LBS surface (mm)"},
                        {"unit", "mm"},
                        {"min", distance_range_.to_json(0.0)[0]},
                        {"max", distance_range_.to_json(0.0)[1]}}}};
}

SurfaceMesh RenderSurface::read(const fs::path& path) {
  try {
    return read_surface(path);
  } catch (const MeshError& e) {
    throw ReportError(e.what());
  }
}

void RenderSurface::read_bones(const fs::path& path, std::size_t frame_count) {
  has_bones_ = true;
  const json b = read_json(path);
  auto fail = [&](const std::string& what) { throw ReportError(fmt::format("{}: {}", path.string(), what)); };
  if (!b.is_object() || !b.contains("bones") || !b.at("bones").is_array() || !b.contains("frames") ||
      !b.at("frames").is_array())
    fail("not a bones file: it needs \"bones\" (names) and \"frames\" (segments) arrays");
  for (const json& n : b.at("bones")) {
    if (!n.is_string()) fail("a bone's name is not a string");
    bone_names_.push_back(n.get<std::string>());
  }
  const json& frames = b.at("frames");
  if (frames.size() != frame_count) fail(fmt::format("{} frames, but frames.pvd has {}", frames.size(), frame_count));
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const json* segments = frames[i].is_object() && frames[i].contains("segments") ? &frames[i].at("segments") : nullptr;
    if (!segments || !segments->is_array() || segments->size() != bone_names_.size())
      fail(fmt::format("frame {} does not have one segment for each of the {} bones", i, bone_names_.size()));
    std::vector<double> flat;
    for (const json& s : *segments) {
      if (!s.is_array() || s.size() != 6) fail(fmt::format("frame {}: a segment is not [ax, ay, az, bx, by, bz]", i));
      for (const json& v : s) {
        if (!v.is_number() || !std::isfinite(v.get<double>()))
          fail(fmt::format("frame {}: a segment has a value that is not a finite number", i));
        flat.push_back(v.get<double>());
      }
    }
    bones_.push_back(std::move(flat));
  }
}

void RenderSurface::group_normals(const SurfaceMesh& s) {
  const double agree = std::cos(8.0 * std::numbers::pi / 180.0);
  std::map<std::array<double, 3>, std::vector<std::uint32_t>> at;  // position -> its groups' first vertices
  groups_.resize(static_cast<std::size_t>(vertex_count_));
  std::uint32_t count = 0;
  for (Eigen::Index v = 0; v < vertex_count_; ++v) {
    std::vector<std::uint32_t>& here = at[{s.vertices(0, v), s.vertices(1, v), s.vertices(2, v)}];
    std::uint32_t g = count;
    for (const std::uint32_t first : here)
      if (s.normals.cols() == 0 || s.normals.col(first).dot(s.normals.col(v)) >= agree * s.normals.col(first).norm() * s.normals.col(v).norm()) {
        g = groups_[first];
        break;
      }
    if (g == count) {
      here.push_back(static_cast<std::uint32_t>(v));
      ++count;
    }
    groups_[static_cast<std::size_t>(v)] = g;
  }
}

}  // namespace snh::report_internal
