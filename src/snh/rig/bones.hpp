#pragma once
// Bones and the flesh they hold (docs/design.md): a bone is the segment from a joint to each of its child
// joints (a leaf joint with no child is a point), moving rigidly with the joint; the volume vertices inside
// a bone's capsule are bound to it and follow it exactly (hard constraints, as HOBAK binds them); those in a
// shell around the capsule may be bound softly, by springs toward where the bone carries them.
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "snh/rig/skeleton.hpp"

namespace snh {

struct Bone {
  std::string name;    ///< "joint" for a point, "joint>child" for a segment
  int joint = 0;       ///< the joint it moves with
  int child = -1;      ///< the child joint its segment reaches; −1 for a point
  Eigen::Vector3d a, b;  ///< the segment's ends at rest (world); a == b for a point
  double radius = 0.0;   ///< capsule radius
};

/// The bones of a skeleton at rest (radius 0): one per (joint, child) pair, one point per childless joint.
///   rest_world  the joints' world transforms at rest (Skeleton::world of the rest pose)
[[nodiscard]] std::vector<Bone> bones_of(const Skeleton& skeleton, const std::vector<Eigen::Affine3d>& rest_world);

/// Distance from p to the segment [a, b].
[[nodiscard]] double segment_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p);

/// How a surface lies around the bones, per bone: the surface vertices whose closest bone it is (the first of
/// equally close ones), how many and their mean distance to it, and its distance to the nearest surface vertex.
struct BoneReach {
  std::vector<int> closest_of;  ///< how many surface vertices have this bone as their closest
  std::vector<double> mean;     ///< their mean distance to it (0 where there are none)
  std::vector<double> nearest;  ///< the distance to the nearest surface vertex
};
///   surface  3 by #s surface vertices
[[nodiscard]] BoneReach bone_reach(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& surface);

/// The default capsule radius of every bone: half the mean distance from the bone to the surface vertices
/// nearest to it (the vertices whose closest bone it is; a bone that is closest to none gets half the
/// distance to the nearest surface vertex).
[[nodiscard]] std::vector<double> default_radii(const BoneReach& reach);
///   surface  3 by #s surface vertices
[[nodiscard]] std::vector<double> default_radii(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& surface);

/// Volume vertices bound to bones: those within some bone's capsule, each bound to the bone whose capsule
/// holds it most deeply (largest radius − distance). Lists are in vertex order.
struct Binding {
  std::vector<int> vertex;  ///< bound volume vertices
  std::vector<int> bone;    ///< the bone of each
  [[nodiscard]] std::vector<int> count_per_bone(int bones) const;
};
/// Which bones may hold which volume vertex (a character's meshes kept apart: a solid only by the bones of the
/// joints its skin is weighted to); empty: every bone may hold every vertex.
using BoneAccess = std::function<bool(Eigen::Index vertex, int bone)>;
///   X  3 by #V volume rest positions
[[nodiscard]] Binding bind_to_bones(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& X, const BoneAccess& may = {});

/// Per volume vertex (of `vertices`) the joint whose bone binds it, −1 for a vertex no bone binds.
[[nodiscard]] std::vector<int> bound_joints(const Binding& binding, const std::vector<Bone>& bones, Eigen::Index vertices);

/// A binding split at the joints: `released` holds the bound vertices that share a cell with a vertex bound to
/// a bone of another joint (such a cell spans a joint, and two rigid motions at once crush or tear it as the
/// joint bends: Newton stalls next to it), `kept` the rest, so that no cell is held by two joints.
struct JointSplit {
  Binding kept, released;
};
///   cells  the volume's cells (vertex indices per column); vertices  the volume's vertex count
[[nodiscard]] JointSplit split_at_joints(const Binding& binding, const std::vector<Bone>& bones, const Eigen::MatrixXi& cells,
                                         Eigen::Index vertices);

/// Volume vertices bound softly (pulled toward where their bone carries them by a spring, not held): those
/// outside every capsule but within `shell` of one (0 < distance − radius < shell) and not in `hard`, each
/// to the bone whose capsule is nearest, with a weight falling linearly from 1 at the capsule to 0 at the
/// shell's outer edge, so the flesh's hold on the bone fades out smoothly. Lists are in vertex order.
struct SoftBinding : Binding {
  std::vector<double> weight;  ///< per vertex, in (0, 1]
};
[[nodiscard]] SoftBinding soft_bind_to_bones(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& X, double shell,
                                             const Binding& hard, const BoneAccess& may = {});
/// `soft` with `more` added at weight w, in vertex order (a vertex in both keeps its entry in `soft`).
[[nodiscard]] SoftBinding merge_soft(const SoftBinding& soft, const Binding& more, double w);

}  // namespace snh
