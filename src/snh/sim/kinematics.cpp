#include "snh/sim/kinematics.hpp"

#include <algorithm>

#include <Eigen/Geometry>

namespace snh {
namespace {

template <class M>
double progress(const M& m, double t) {
  return std::clamp((t - m.start) / (m.end - m.start), 0.0, 1.0);
}

}  // namespace

Eigen::Affine3d motion_transform(const std::vector<Motion>& motions, const Eigen::Vector3d& centroid, double t) {
  Eigen::Affine3d A = Eigen::Affine3d::Identity();
  for (const Motion& motion : motions)
    std::visit(
        [&](const auto& m) {
          using M = std::decay_t<decltype(m)>;
          const double p = progress(m, t);
          if constexpr (std::is_same_v<M, Translate>) {
            A.pretranslate(p * m.by);
          } else {
            const Eigen::Vector3d c = m.center.value_or(A * centroid);
            Eigen::Matrix3d L;
            if constexpr (std::is_same_v<M, Rotate>) L = Eigen::AngleAxisd(p * m.radians, m.axis).toRotationMatrix();
            else L = (Eigen::Vector3d::Ones() + p * (m.factors - Eigen::Vector3d::Ones())).asDiagonal();
            Eigen::Affine3d about_c = Eigen::Affine3d::Identity();  // x ↦ L(x − c) + c, after what came before
            about_c.linear() = L;
            about_c.translation() = c - L * c;
            A = about_c * A;
          }
        },
        motion);
  return A;
}

void ScriptedMotion::targets(double t, Eigen::Matrix3Xd& P) const {
  P = base_;
  for (const Motion& motion : motions_)
    std::visit(
        [&](const auto& m) {
          using M = std::decay_t<decltype(m)>;
          const double p = progress(m, t);
          if constexpr (std::is_same_v<M, Translate>) {
            P.colwise() += p * m.by;
          } else if constexpr (std::is_same_v<M, Rotate>) {
            const Eigen::Vector3d c = m.center.value_or(P.rowwise().mean());
            const Eigen::Matrix3d R = Eigen::AngleAxisd(p * m.radians, m.axis).toRotationMatrix();
            P = (R * (P.colwise() - c)).colwise() + c;
          } else {
            const Eigen::Vector3d c = m.center.value_or(P.rowwise().mean());
            const Eigen::Vector3d f = Eigen::Vector3d::Ones() + p * (m.factors - Eigen::Vector3d::Ones());
            P = (f.asDiagonal() * (P.colwise() - c)).colwise() + c;
          }
        },
        motion);
}

}  // namespace snh
