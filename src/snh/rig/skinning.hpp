#pragma once
// Linear blend skinning (docs/design.md): each vertex moved by its joints' world · inverse-bind transforms,
// blended by its weights. The comparison flesh simulation is measured against.
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "snh/rig/model.hpp"

namespace snh {

/// The model's vertices (its own order, 3 by #v) posed by linear blend skinning.
///   world  the joints' world transforms (Skeleton::world of a pose)
[[nodiscard]] Eigen::Matrix3Xd skin_vertices(const RiggedModel& model, const std::vector<Eigen::Affine3d>& world);

}  // namespace snh
