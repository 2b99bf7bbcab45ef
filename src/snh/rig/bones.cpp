#include "snh/rig/bones.hpp"

#include <algorithm>
#include <limits>

namespace snh {

std::vector<Bone> bones_of(const Skeleton& skeleton, const std::vector<Eigen::Affine3d>& rest_world) {
  std::vector<Bone> bones;
  const std::vector<std::vector<int>> children = skeleton.children();
  for (int j = 0; j < skeleton.size(); ++j) {
    const Eigen::Vector3d a = rest_world[j].translation();
    if (children[j].empty()) {
      bones.push_back({.name = skeleton.joints[j].name, .joint = j, .child = -1, .a = a, .b = a});
      continue;
    }
    for (int c : children[j])
      bones.push_back({.name = skeleton.joints[j].name + ">" + skeleton.joints[c].name, .joint = j, .child = c, .a = a,
                       .b = rest_world[c].translation()});
  }
  return bones;
}

double segment_distance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = b - a;
  const double len2 = d.squaredNorm();
  const double s = len2 > 0.0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + s * d - p).norm();
}

BoneReach bone_reach(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& surface) {
  const int n = static_cast<int>(bones.size());
  BoneReach r{.closest_of = std::vector<int>(n, 0), .mean = std::vector<double>(n, 0.0),
              .nearest = std::vector<double>(n, std::numeric_limits<double>::infinity())};
  for (Eigen::Index v = 0; v < surface.cols(); ++v) {
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int b = 0; b < n; ++b) {
      const double d = segment_distance(bones[b].a, bones[b].b, surface.col(v));
      r.nearest[b] = std::min(r.nearest[b], d);
      if (d < best_d) best_d = d, best = b;
    }
    if (best >= 0) r.mean[best] += best_d, ++r.closest_of[best];
  }
  for (int b = 0; b < n; ++b)
    if (r.closest_of[b] > 0) r.mean[b] /= r.closest_of[b];
  return r;
}

std::vector<double> default_radii(const BoneReach& reach) {
  std::vector<double> radii(reach.mean.size());
  for (std::size_t b = 0; b < radii.size(); ++b) radii[b] = 0.5 * (reach.closest_of[b] > 0 ? reach.mean[b] : reach.nearest[b]);
  return radii;
}

std::vector<double> default_radii(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& surface) {
  return default_radii(bone_reach(bones, surface));
}

std::vector<int> Binding::count_per_bone(int bones) const {
  std::vector<int> counts(bones, 0);
  for (int b : bone) ++counts[b];
  return counts;
}

Binding bind_to_bones(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& X, const BoneAccess& may) {
  Binding out;
  for (Eigen::Index v = 0; v < X.cols(); ++v) {
    int best = -1;
    double depth = 0.0;  // radius − distance: > 0 inside; ties go to the first bone
    for (int b = 0; b < static_cast<int>(bones.size()); ++b) {
      if (may && !may(v, b)) continue;
      const double d = bones[b].radius - segment_distance(bones[b].a, bones[b].b, X.col(v));
      if (d >= 0.0 && (best < 0 || d > depth)) best = b, depth = d;
    }
    if (best >= 0) {
      out.vertex.push_back(static_cast<int>(v));
      out.bone.push_back(best);
    }
  }
  return out;
}

std::vector<int> bound_joints(const Binding& binding, const std::vector<Bone>& bones, Eigen::Index vertices) {
  std::vector<int> joint(static_cast<std::size_t>(vertices), -1);
  for (std::size_t i = 0; i < binding.vertex.size(); ++i) joint[static_cast<std::size_t>(binding.vertex[i])] = bones[binding.bone[i]].joint;
  return joint;
}

JointSplit split_at_joints(const Binding& binding, const std::vector<Bone>& bones, const Eigen::MatrixXi& cells,
                           Eigen::Index vertices) {
  const std::vector<int> joint = bound_joints(binding, bones, vertices);  // the joint each bound vertex moves with
  std::vector<bool> release(static_cast<std::size_t>(vertices), false);
  for (Eigen::Index c = 0; c < cells.cols(); ++c) {
    int first = -1;
    bool mixed = false;
    for (Eigen::Index k = 0; k < cells.rows(); ++k) {
      const int j = joint[static_cast<std::size_t>(cells(k, c))];
      if (j < 0) continue;
      if (first < 0) first = j;
      else mixed = mixed || j != first;
    }
    if (mixed)
      for (Eigen::Index k = 0; k < cells.rows(); ++k)
        if (joint[static_cast<std::size_t>(cells(k, c))] >= 0) release[static_cast<std::size_t>(cells(k, c))] = true;
  }
  JointSplit out;
  for (std::size_t i = 0; i < binding.vertex.size(); ++i) {
    Binding& to = release[static_cast<std::size_t>(binding.vertex[i])] ? out.released : out.kept;
    to.vertex.push_back(binding.vertex[i]);
    to.bone.push_back(binding.bone[i]);
  }
  return out;
}

SoftBinding soft_bind_to_bones(const std::vector<Bone>& bones, const Eigen::Matrix3Xd& X, double shell,
                               const Binding& hard, const BoneAccess& may) {
  SoftBinding out;
  if (!(shell > 0.0)) return out;
  std::vector<bool> held(static_cast<std::size_t>(X.cols()), false);
  for (int v : hard.vertex) held[static_cast<std::size_t>(v)] = true;
  for (Eigen::Index v = 0; v < X.cols(); ++v) {
    if (held[static_cast<std::size_t>(v)]) continue;
    int best = -1;
    double gap = 0.0;  // distance − radius: > 0 outside the capsule; ties go to the first bone
    for (int b = 0; b < static_cast<int>(bones.size()); ++b) {
      if (may && !may(v, b)) continue;
      const double d = segment_distance(bones[b].a, bones[b].b, X.col(v)) - bones[b].radius;
      if (best < 0 || d < gap) best = b, gap = d;
    }
    if (best >= 0 && gap < shell) {
      out.vertex.push_back(static_cast<int>(v));
      out.bone.push_back(best);
      out.weight.push_back(1.0 - std::max(gap, 0.0) / shell);
    }
  }
  return out;
}

SoftBinding merge_soft(const SoftBinding& soft, const Binding& more, double w) {
  SoftBinding out;
  std::size_t a = 0, b = 0;
  while (a < soft.vertex.size() || b < more.vertex.size()) {
    const bool take_soft = b >= more.vertex.size() || (a < soft.vertex.size() && soft.vertex[a] <= more.vertex[b]);
    if (take_soft) {
      if (b < more.vertex.size() && more.vertex[b] == soft.vertex[a]) ++b;
      out.vertex.push_back(soft.vertex[a]);
      out.bone.push_back(soft.bone[a]);
      out.weight.push_back(soft.weight[a]);
      ++a;
    } else {
      out.vertex.push_back(more.vertex[b]);
      out.bone.push_back(more.bone[b]);
      out.weight.push_back(w);
      ++b;
    }
  }
  return out;
}

}  // namespace snh
