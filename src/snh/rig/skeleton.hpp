#pragma once
// A skeleton (docs/design.md): joints with a parent and a rest transform local to it, and forward
// kinematics from local poses to world transforms.
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "snh/rig/transform.hpp"

namespace snh {

struct Joint {
  std::string name;
  int parent = -1;   ///< index of the parent joint; -1 for a root
  Transform rest;    ///< local to the parent (for a root: to the model, every non-joint ancestor folded in)
};

/// A pose: one local transform per joint, in the skeleton's joint order.
using Pose = std::vector<Transform>;

struct Skeleton {
  std::vector<Joint> joints;  ///< any order (a skin's joint order); the parent links form a forest

  [[nodiscard]] int size() const { return static_cast<int>(joints.size()); }
  /// The rest pose (every joint's `rest`).
  [[nodiscard]] Pose rest_pose() const;
  /// World (model) transform of every joint for a pose: parent world · local, through the hierarchy.
  [[nodiscard]] std::vector<Eigen::Affine3d> world(const Pose& pose) const;
  /// The index of the joint of this name; -1 if none.
  [[nodiscard]] int find(std::string_view name) const;
  /// The children of each joint, in joint order.
  [[nodiscard]] std::vector<std::vector<int>> children() const;
};

}  // namespace snh
