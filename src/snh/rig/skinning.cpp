#include "snh/rig/skinning.hpp"

#include <stdexcept>

#include <fmt/format.h>

namespace snh {

Eigen::Matrix3Xd skin_vertices(const RiggedModel& model, const std::vector<Eigen::Affine3d>& world) {
  const std::size_t joints = model.skeleton.joints.size();
  if (world.size() != joints || model.inverse_bind.size() != joints)
    throw std::invalid_argument(fmt::format("skinning {} joints with {} world transforms and {} inverse bind matrices",
                                            joints, world.size(), model.inverse_bind.size()));
  const Eigen::Index n = model.vertices.cols();
  if (model.joint_index.cols() != n || model.joint_weight.cols() != n)
    throw std::invalid_argument(fmt::format("skinning {} vertices with joints and weights for {} and {}", n,
                                            model.joint_index.cols(), model.joint_weight.cols()));
  // The skinning matrix of each joint: model space at bind → the joint's frame → model space posed.
  std::vector<Eigen::Matrix<double, 3, 4>> skin(joints);
  for (std::size_t j = 0; j < joints; ++j) skin[j] = (world[j].matrix() * model.inverse_bind[j]).topRows<3>();

  Eigen::Matrix3Xd out(3, n);
  for (Eigen::Index v = 0; v < n; ++v) {
    const Eigen::Vector4d x = model.vertices.col(v).homogeneous();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) {
      const double w = model.joint_weight(k, v);
      if (w == 0.0) continue;
      const int j = model.joint_index(k, v);
      if (j < 0 || static_cast<std::size_t>(j) >= joints)
        throw std::invalid_argument(fmt::format("vertex {} is bound to joint {}, but there are {} joints", v, j, joints));
      sum += w * (skin[static_cast<std::size_t>(j)] * x);
    }
    if (!sum.allFinite()) throw std::invalid_argument(fmt::format("vertex {} skins to a position that is not finite", v));
    out.col(v) = sum;
  }
  return out;
}

}  // namespace snh
