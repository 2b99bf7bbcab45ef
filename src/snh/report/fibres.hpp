#pragma once
// A run's muscle fibres in its report (docs/report.md, docs/muscles.md): from muscles.json, per frame each
// muscle cell's fibre drawn as a short segment through the cell's centre along F a (F the cell's best
// affine map from rest, a its rest fibre), and each muscle's activation, by which the page colours them.
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

class ReportFibres {
 public:
  /// j: muscles.json as read (its path `file` names it in messages); rest: the run's rest mesh; frame_count:
  /// the frames the report shows. Throws ReportError (one line naming the file) for a file that does not
  /// fit: a cell out of range, a fibre that is not three finite numbers, fewer activations than frames.
  ReportFibres(const nlohmann::json& j, const std::string& file, const VolumeMesh& rest, std::size_t frame_count);
  /// data.js's "fibres": {"muscles": names, "count": fibres, "muscle": base64 Uint32 (each fibre's muscle)}.
  [[nodiscard]] nlohmann::json summary() const;
  /// Frame i's {"segments": base64 Float32 (6 per fibre), "activation": [one per muscle]} at positions x (3 by
  /// #V); `lo` and `hi` grow to the segments' ends.
  [[nodiscard]] nlohmann::json frame(std::size_t i, const Eigen::Matrix3Xd& x, Eigen::Vector3d& lo, Eigen::Vector3d& hi) const;
  [[nodiscard]] std::size_t count() const { return cells_.size(); }

 private:
  const VolumeMesh& rest_;
  std::vector<std::string> names_;
  std::vector<std::vector<double>> activation_;  ///< per muscle, per frame
  std::vector<int> cells_;                       ///< per fibre, its cell
  std::vector<std::uint32_t> muscle_;            ///< per fibre, its muscle
  std::vector<Eigen::Vector3d> direction_;       ///< per fibre, unit, rest frame
  std::vector<double> half_;                     ///< per fibre, half the segment's rest length (0.4 × the cell's size)
};

}  // namespace snh
