#pragma once
// Pieces of the report's writer (report.cpp) kept apart by concern; not part of the library's interface:
// reading a JSON input, base64 arrays, value ranges, and a flesh run's render surface (render_surface.cpp).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "snh/io/base64.hpp"
#include "snh/io/surface_read.hpp"

namespace snh::report_internal {

using json = nlohmann::json;
namespace fs = std::filesystem;

/// The JSON file at path, checked first as every input is (io/input_file: a directory, a FIFO, a device or
/// a file over 1 GiB fails at once with one line). Throws ReportError.
json read_json(const fs::path& path);

template <class T>
std::string encode(const std::vector<T>& v) { return base64_encode(v.data(), v.size() * sizeof(T)); }

struct Range {
  double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  [[nodiscard]] json to_json(double fallback) const {
    return lo <= hi ? json::array({lo, hi}) : json::array({fallback, fallback});
  }
};

/// The render surface of a flesh run: for each frame NNN.vtu, surface/NNN.obj (the surface simulated as
/// flesh) and lbs/NNN.obj (posed by linear blend skinning), every file with the triangles of surface/000.obj;
/// and, when bones.json is there, the bones' segments of every frame. frame() gives what a frame's file
/// holds of it, with the flesh's signed distance from the skinned surface at each vertex (positive outside
/// it, in millimetres: `mm_per_unit` is the model's), summary() the "render" object of data.js, with the
/// vertices' normal groups (smooth shading: one normal per group) and the distances' range and extremes per frame.
class RenderSurface {
 public:
  RenderSurface(const fs::path& dir, std::size_t frame_count, double mm_per_unit);
  /// Frame i's positions (the frame's .vtu file is `vtu`): {"flesh", "lbs", "distance", "bones"}, base64 Float32.
  json frame(std::size_t i, const std::string& vtu);
  /// The largest distance outside and inside the skinned surface of each frame, in millimetres.
  [[nodiscard]] const json& outside() const { return outside_; }
  [[nodiscard]] const json& inside() const { return inside_; }
  [[nodiscard]] json summary() const;

 private:
  static SurfaceMesh read(const fs::path& path);
  /// bones.json: {"bones": [names], "frames": [{"time", "segments": [[ax, ay, az, bx, by, bz] per bone]} per frame]}.
  void read_bones(const fs::path& path, std::size_t frame_count);
  /// groups_: vertices at one position whose normals in surface/000.obj agree within about 8° share a group
  /// (a seam's copies do, a hard edge's do not); all at one position where the file has no normals.
  void group_normals(const SurfaceMesh& s);

  fs::path dir_;
  double mm_per_unit_;
  Eigen::Matrix3Xi triangles_;
  Eigen::Index vertex_count_ = 0;
  std::vector<std::uint32_t> groups_;  ///< per vertex: its normal group
  Range distance_range_;
  json outside_ = json::array(), inside_ = json::array();
  std::vector<std::string> bone_names_;
  bool has_bones_ = false;                  ///< bones.json was read
  std::vector<std::vector<double>> bones_;  ///< per frame: 6 values per bone
  Range bounds_[3];
};

}  // namespace snh::report_internal
