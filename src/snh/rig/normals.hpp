#pragma once
// Vertex normals of a deforming skin (docs/flesh.md "Back into your animation tool"): the caches carry the
// skin's normals at every frame, computed from its triangles as they move, smooth where the model is smooth
// and split where the model splits them (a hard edge, a UV seam is not one).
#include <vector>

#include <Eigen/Core>

#include "snh/rig/model.hpp"

namespace snh {

/// Which model vertices share one normal: vertices at the same position (the weld) whose normals in the file
/// agree within about 8° (all of them, where the file has no normals). Group ids 0 … groups − 1 per vertex.
struct NormalGroups {
  std::vector<int> group;  ///< per model vertex
  int groups = 0;
  double sign = 1.0;       ///< −1 where the triangles' winding gives normals against the file's
};

[[nodiscard]] NormalGroups normal_groups(const RiggedModel& model);

/// Unit normals (3 by #v, model order) of the skin at `positions` (3 by #v): per group, the sum over its
/// triangles' corners of each face's unit normal times the corner's angle; a group whose triangles have no
/// area keeps (0, 0, 0).
[[nodiscard]] Eigen::Matrix3Xd vertex_normals(const RiggedModel& model, const NormalGroups& groups, const Eigen::Matrix3Xd& positions);

}  // namespace snh
