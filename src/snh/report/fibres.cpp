#include "snh/report/fibres.hpp"

#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "snh/io/base64.hpp"
#include "snh/report/report.hpp"

namespace snh {

using json = nlohmann::json;

ReportFibres::ReportFibres(const json& j, const std::string& file, const VolumeMesh& rest, std::size_t frame_count) : rest_(rest) {
  const auto fail = [&](const std::string& what) { throw ReportError(fmt::format("{}: {}", file, what)); };
  if (!j.is_object() || !j.contains("regions") || !j.at("regions").is_array()) fail("not a muscles file: it needs a \"regions\" array");
  for (const json& r : j.at("regions")) {
    if (!r.is_object() || r.value("kind", "") != "muscle") continue;
    const std::string name = r.value("name", "");
    const json& cells = r.contains("cells") ? r.at("cells") : json();
    const json& dirs = r.contains("fibre_directions") ? r.at("fibre_directions") : json();
    const json& act = r.contains("activation") ? r.at("activation") : json();
    if (!cells.is_array() || !dirs.is_array() || cells.size() != dirs.size())
      fail(fmt::format("muscle \"{}\": cells and fibre_directions must be arrays of one length", name));
    if (!act.is_array() || act.size() < frame_count)
      fail(fmt::format("muscle \"{}\": {} activations for {} frames", name, act.is_array() ? act.size() : 0, frame_count));
    std::vector<double> a;
    for (const json& v : act) {
      if (!v.is_number() || !(v.get<double>() >= 0.0 && v.get<double>() <= 1.0)) fail(fmt::format("muscle \"{}\": an activation is not in [0, 1]", name));
      a.push_back(v.get<double>());
    }
    for (std::size_t k = 0; k < cells.size(); ++k) {
      if (!cells[k].is_number_integer() || cells[k].get<long long>() < 0 || cells[k].get<long long>() >= rest.cell_count())
        fail(fmt::format("muscle \"{}\": cell {} is not one of the mesh's {} cells", name, cells[k].dump(), rest.cell_count()));
      const json& d = dirs[k];
      Eigen::Vector3d v;
      for (int c = 0; c < 3; ++c) {
        if (!d.is_array() || d.size() != 3 || !d[c].is_number()) fail(fmt::format("muscle \"{}\": fibre {} is not 3 numbers", name, k));
        v[c] = d[c].get<double>();
      }
      if (!v.allFinite() || !(v.norm() > 0.0)) fail(fmt::format("muscle \"{}\": fibre {} is not a finite nonzero vector", name, k));
      const int cell = static_cast<int>(cells[k].get<long long>());
      cells_.push_back(cell);
      muscle_.push_back(static_cast<std::uint32_t>(names_.size()));
      direction_.push_back(v.normalized());
      half_.push_back(0.4 * std::cbrt(std::abs(cell_volume(rest, cell))));
    }
    names_.push_back(name);
    activation_.push_back(std::move(a));
  }
}

json ReportFibres::summary() const {
  return {{"muscles", names_}, {"count", cells_.size()}, {"muscle", base64_encode(muscle_.data(), muscle_.size() * sizeof(std::uint32_t))}};
}

json ReportFibres::frame(std::size_t i, const Eigen::Matrix3Xd& x, Eigen::Vector3d& lo, Eigen::Vector3d& hi) const {
  std::vector<float> segments(6 * cells_.size());
  const Eigen::Index n = rest_.cells.rows();
  for (std::size_t k = 0; k < cells_.size(); ++k) {
    // The affine map that fits the cell's corners best (exact for a tet): F = (Σ dx dXᵀ)(Σ dX dXᵀ)⁻¹.
    Eigen::Vector3d X0 = Eigen::Vector3d::Zero(), x0 = Eigen::Vector3d::Zero();
    for (Eigen::Index c = 0; c < n; ++c) {
      X0 += rest_.vertices.col(rest_.cells(c, cells_[k])) / static_cast<double>(n);
      x0 += x.col(rest_.cells(c, cells_[k])) / static_cast<double>(n);
    }
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero(), B = Eigen::Matrix3d::Zero();
    for (Eigen::Index c = 0; c < n; ++c) {
      const Eigen::Vector3d dX = rest_.vertices.col(rest_.cells(c, cells_[k])) - X0, dx = x.col(rest_.cells(c, cells_[k])) - x0;
      A += dx * dX.transpose();
      B += dX * dX.transpose();
    }
    const Eigen::Vector3d d = A * B.inverse() * direction_[k] * half_[k];
    for (int c = 0; c < 3; ++c) {
      segments[6 * k + c] = static_cast<float>(x0[c] - d[c]);
      segments[6 * k + 3 + c] = static_cast<float>(x0[c] + d[c]);
    }
    lo = lo.cwiseMin(x0 - d.cwiseAbs());
    hi = hi.cwiseMax(x0 + d.cwiseAbs());
  }
  json act = json::array();
  for (const std::vector<double>& a : activation_) act.push_back(a[i]);
  return {{"segments", base64_encode(segments.data(), segments.size() * sizeof(float))}, {"activation", act}};
}

}  // namespace snh
