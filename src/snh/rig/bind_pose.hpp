#pragma once
// The bind pose of a rigged model (docs/flesh.md "Bind pose and rest pose"): where its skin and its joints
// are when the skin was bound to them. A file stores the skin at the bind pose and the joints at their rest
// transforms; the inverse bind matrices tie the two. In most files the rest pose is the bind pose, but not
// in all: an exporter may leave the armature's own transform (a scale of 100 from centimetres, a turn from
// Z-up to Y-up) out of the skin, so that the rest pose places the skin elsewhere, scaled and turned; or a
// character bound in one pose rests in another.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "snh/rig/model.hpp"

namespace snh {

/// A similarity transform x ↦ s R x + t.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  [[nodiscard]] Eigen::Affine3d affine() const;
  /// The rotation's angle in radians (0 to π).
  [[nodiscard]] double angle() const;
};

/// The similarity that best maps the points `from` onto `to` in the least-squares sense (Umeyama 1991: the
/// rotation from the SVD of the cross-covariance, a reflection excluded). Both 3 by n, n ≥ 1.
[[nodiscard]] Similarity fit_similarity(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to);

struct BindPose {
  /// Where the rest pose puts the skin as a whole: the similarity nearest, over the skin as stored, to the root
  /// joint's skinning matrix at rest (rest · inverse bind; the first joint without a parent); exactly the
  /// identity when that moves the skin by less than 1e-6 of the model's size.
  Similarity placement;
  bool placed = false;                 ///< placement is not the identity
  /// The joints' frames at the bind pose, in the placed model's space: the rest pose's frames where they agree
  /// with the inverse bind matrices (to 1e-4 of the model's size), else the inverse bind matrices'.
  std::vector<Eigen::Affine3d> joints;
  bool rest_is_bind = true;
  std::string worst_joint;             ///< the joint whose rest and bind frames differ most
  double worst_offset = 0.0;           ///< by this distance (model units, after placement)
};

/// The model's bind pose. `model` is placed: its vertices (as stored and welded) moved by the placement and
/// its inverse bind matrices made to match, so that linear blend skinning gives the same posed skin as
/// before and the skin at rest stands where the rest pose puts it.
[[nodiscard]] BindPose place_at_bind_pose(RiggedModel& model);

/// One line for a run's header on what place_at_bind_pose found; empty when the rest pose is the bind pose
/// and nothing was placed.
[[nodiscard]] std::string describe(const BindPose& bind);

}  // namespace snh
