#pragma once
// A joint's local transform as glTF stores it (docs/design.md): translation, rotation, scale, composed as
// T · R · S (glTF 2.0 §5.25 "node").
#include <Eigen/Geometry>

namespace snh {

struct Transform {
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();

  /// The 4 by 4 affine map T · R · S.
  [[nodiscard]] Eigen::Affine3d matrix() const {
    Eigen::Affine3d m = Eigen::Affine3d::Identity();
    m.translate(translation);
    m.rotate(rotation.normalized().toRotationMatrix());
    m.scale(scale);
    return m;
  }
};

}  // namespace snh
