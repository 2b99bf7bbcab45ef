#pragma once
// A summary of a mesh's rest-state quality (issue 3): counts, rest-volume range, worst edge ratio.
#include <string>

#include "snh/fem/rest_state.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

struct MeshQuality {
  Eigen::Index vertices = 0, cells = 0;
  double min_volume = 0.0, max_volume = 0.0;  ///< rest volume per cell
  double worst_edge_ratio = 0.0;              ///< max over cells of longest / shortest cell edge
  Eigen::Index worst_cell = -1;               ///< the cell with that ratio
};

/// Longest over shortest edge of every cell (+∞ for a cell with a zero-length edge).
[[nodiscard]] Eigen::VectorXd cell_edge_ratios(const VolumeMesh& mesh);

/// Computes the summary; rest is compute_rest_state(mesh).
[[nodiscard]] MeshQuality mesh_quality(const VolumeMesh& mesh, const RestState& rest);

/// "6000 tets, rest volume 0.001333 .. 0.001333, worst edge ratio 1.732 (cell 0)"
[[nodiscard]] std::string describe(const MeshQuality& q, CellType type);

}  // namespace snh
