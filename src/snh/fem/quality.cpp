#include "snh/fem/quality.hpp"

#include <algorithm>
#include <limits>

#include <fmt/format.h>

namespace snh {
namespace {

// Cell edges as pairs of local corners.
constexpr int kTetEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
constexpr int kHexEdges[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3},
                                  {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

template <std::size_t E>
double edge_ratio(const VolumeMesh& m, Eigen::Index c, const int (&edges)[E][2]) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& e : edges) {
    const double len = (m.vertices.col(m.cells(e[0], c)) - m.vertices.col(m.cells(e[1], c))).norm();
    lo = std::min(lo, len);
    hi = std::max(hi, len);
  }
  return lo > 0.0 ? hi / lo : std::numeric_limits<double>::infinity();
}

}  // namespace

Eigen::VectorXd cell_edge_ratios(const VolumeMesh& mesh) {
  Eigen::VectorXd r(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    r[c] = mesh.type == CellType::tet4 ? edge_ratio(mesh, c, kTetEdges) : edge_ratio(mesh, c, kHexEdges);
  return r;
}

MeshQuality mesh_quality(const VolumeMesh& mesh, const RestState& rest) {
  MeshQuality q;
  q.vertices = mesh.vertex_count();
  q.cells = mesh.cell_count();
  const Eigen::VectorXd vol = rest_volumes(rest);
  if (vol.size() > 0) {
    q.min_volume = vol.minCoeff();
    q.max_volume = vol.maxCoeff();
  }
  const Eigen::VectorXd ratios = cell_edge_ratios(mesh);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    const double r = ratios[c];
    if (r > q.worst_edge_ratio) {
      q.worst_edge_ratio = r;
      q.worst_cell = c;
    }
  }
  return q;
}

std::string describe(const MeshQuality& q, CellType type) {
  return fmt::format("{} {}, rest volume {:.6g} .. {:.6g}, worst edge ratio {:.4g} (cell {})", q.cells,
                     type == CellType::tet4 ? "tets" : "hexes", q.min_volume, q.max_volume, q.worst_edge_ratio,
                     q.worst_cell);
}

}  // namespace snh
