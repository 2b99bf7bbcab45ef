#include "snh/rig/normals.hpp"

#include <cmath>
#include <utility>
#include <vector>

namespace snh {

NormalGroups normal_groups(const RiggedModel& model) {
  const Eigen::Index n = model.vertices.cols();
  const bool file_normals = model.normals.cols() == n && n > 0;
  NormalGroups g;
  g.group.assign(static_cast<std::size_t>(n), -1);
  // Per welded vertex, the groups made so far and a normal of each.
  const bool welded = model.weld.size() == static_cast<std::size_t>(n);
  std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> at(welded ? static_cast<std::size_t>(model.surface_vertices.cols())
                                                                      : static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v) {
    auto& here = at[welded ? static_cast<std::size_t>(model.weld[static_cast<std::size_t>(v)]) : static_cast<std::size_t>(v)];
    const Eigen::Vector3d normal = file_normals ? Eigen::Vector3d(model.normals.col(v)) : Eigen::Vector3d::Zero();
    int found = -1;
    for (const auto& [id, other] : here)
      if (!file_normals || normal.dot(other) > 0.99 * normal.norm() * other.norm()) {
        found = id;
        break;
      }
    if (found < 0) {
      found = g.groups++;
      here.emplace_back(found, normal);
    }
    g.group[static_cast<std::size_t>(v)] = found;
  }
  if (file_normals) {
    const Eigen::Matrix3Xd rest = vertex_normals(model, g, model.vertices);
    g.sign = (rest.array() * model.normals.array()).sum() < 0.0 ? -1.0 : 1.0;
  }
  return g;
}

Eigen::Matrix3Xd vertex_normals(const RiggedModel& model, const NormalGroups& groups, const Eigen::Matrix3Xd& positions) {
  Eigen::Matrix3Xd sum = Eigen::Matrix3Xd::Zero(3, groups.groups);
  const auto gid = [&](int v) { return groups.group[static_cast<std::size_t>(v)]; };
  for (Eigen::Index t = 0; t < model.triangles.cols(); ++t) {
    const int i[3] = {model.triangles(0, t), model.triangles(1, t), model.triangles(2, t)};
    const Eigen::Vector3d nt = (positions.col(i[1]) - positions.col(i[0])).cross(positions.col(i[2]) - positions.col(i[0]));
    const double len = nt.norm();
    if (!(len > 0.0)) continue;
    // Each corner adds the face's unit normal times its angle there (Thürmer and Wüthrich's weighting, as
    // Blender's): independent of how a polygon was split into triangles and of the triangles' sizes.
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d e1 = positions.col(i[(c + 1) % 3]) - positions.col(i[c]), e2 = positions.col(i[(c + 2) % 3]) - positions.col(i[c]);
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));
      sum.col(gid(i[c])) += (angle / len) * nt;
    }
  }
  Eigen::Matrix3Xd out(3, positions.cols());
  for (Eigen::Index v = 0; v < positions.cols(); ++v) {
    const Eigen::Vector3d s = sum.col(gid(static_cast<int>(v)));
    const double len = s.norm();
    out.col(v) = len > 0.0 ? Eigen::Vector3d(groups.sign * s / len) : Eigen::Vector3d::Zero();
  }
  return out;
}

}  // namespace snh
