#include "snh/rig/bind_pose.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/SVD>
#include <fmt/format.h>

#include "snh/rig/skinning.hpp"

namespace snh {

Eigen::Affine3d Similarity::affine() const {
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.linear() = scale * rotation;
  a.translation() = translation;
  return a;
}

double Similarity::angle() const { return std::acos(std::clamp(0.5 * (rotation.trace() - 1.0), -1.0, 1.0)); }

Similarity fit_similarity(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to) {
  const auto n = static_cast<double>(from.cols());
  const Eigen::Vector3d cf = from.rowwise().mean(), ct = to.rowwise().mean();
  const Eigen::Matrix3Xd a = from.colwise() - cf, b = to.colwise() - ct;
  const Eigen::Matrix3d cross = b * a.transpose() / n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d d = Eigen::Vector3d::Ones();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) d(2) = -1.0;  // no reflection
  Similarity s;
  s.rotation = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
  const double spread = a.squaredNorm() / n;
  s.scale = spread > 0.0 ? svd.singularValues().dot(d) / spread : 1.0;
  s.translation = ct - s.scale * s.rotation * cf;
  return s;
}

BindPose place_at_bind_pose(RiggedModel& model) {
  BindPose out;
  const std::vector<Eigen::Affine3d> rest = model.skeleton.world(model.skeleton.rest_pose());
  const double size = (model.vertices.rowwise().maxCoeff() - model.vertices.rowwise().minCoeff()).norm();

  // The placement: how the rest pose moves the skin with its root joint (its skinning matrix at rest, rest ·
  // inverse bind, as the similarity nearest to it over the skin), identity unless that is more than
  // round-off. The root, not the whole skin: a limb resting bent is not a placement.
  int root = 0;
  while (root < model.skeleton.size() && model.skeleton.joints[static_cast<std::size_t>(root)].parent >= 0) ++root;
  if (root == model.skeleton.size()) root = 0;  // (Skeleton::world refuses cycles: a root exists)
  const Eigen::Affine3d root_skinning(rest[static_cast<std::size_t>(root)].matrix() * model.inverse_bind[static_cast<std::size_t>(root)]);
  Similarity g = fit_similarity(model.vertices, root_skinning * model.vertices);
  const double moved = std::abs(g.scale - 1.0) + g.angle() + g.translation.norm() / std::max(size, 1e-300);
  if (moved > 1e-6) {
    out.placement = g;
    out.placed = true;
    const Eigen::Affine3d to = g.affine(), back = to.inverse();
    model.vertices = to * model.vertices;  // (Affine * 3×n applies to each column)
    model.surface_vertices = to * model.surface_vertices;
    if (model.normals.cols() > 0) model.normals = g.rotation * model.normals;  // a similarity turns normals by its rotation
    for (Eigen::Matrix4d& m : model.inverse_bind) m = m * back.matrix();
  }

  // The joints' bind frames, and how far the rest frames are from them.
  const double placed_size = size * out.placement.scale;
  out.joints.resize(rest.size());
  for (std::size_t j = 0; j < rest.size(); ++j) {
    const Eigen::Affine3d bind(model.inverse_bind[j].inverse());
    const double offset = (bind.translation() - rest[j].translation()).norm() +
                          placed_size * (bind.linear() - rest[j].linear()).norm() / std::max(rest[j].linear().norm(), 1e-300);
    if (offset > out.worst_offset) out.worst_offset = offset, out.worst_joint = model.skeleton.joints[j].name;
    out.joints[j] = bind;
  }
  out.rest_is_bind = out.worst_offset <= 1e-4 * placed_size;
  if (out.rest_is_bind) out.joints = rest;  // the file's rest frames, free of the inverse bind matrices' rounding
  return out;
}

std::string describe(const BindPose& bind) {
  std::string line;
  if (bind.placed) {
    const Eigen::AngleAxisd turn(bind.placement.rotation);
    line = fmt::format("placement: the rest pose puts the skin scaled {:.4g}x, turned {:.1f} degrees about ({:.3f}, {:.3f}, {:.3f}) "
                       "and moved by {:.4g} from where the file stores it (an armature's transform left out of the skin); "
                       "the flesh is built where the rest pose puts it",
                       bind.placement.scale, bind.placement.angle() * 180.0 / std::numbers::pi, turn.axis()(0), turn.axis()(1),
                       turn.axis()(2), bind.placement.translation.norm());
  }
  if (!bind.rest_is_bind)
    line += fmt::format("{}bind pose: the rest pose differs from the pose the skin was bound in (joint {} by {:.4g}); bones are "
                        "placed and the flesh bound in the bind pose, and the animation moves them from there",
                        line.empty() ? "" : "\n", bind.worst_joint, bind.worst_offset);
  return line;
}

}  // namespace snh
