#include "snh/rig/skeleton.hpp"

#include <stdexcept>

#include <fmt/format.h>

namespace snh {

Pose Skeleton::rest_pose() const {
  Pose pose;
  pose.reserve(joints.size());
  for (const Joint& j : joints) pose.push_back(j.rest);
  return pose;
}

std::vector<Eigen::Affine3d> Skeleton::world(const Pose& pose) const {
  const int n = size();
  if (static_cast<int>(pose.size()) != n)
    throw std::invalid_argument(fmt::format("a pose of {} transforms for a skeleton of {} joints", pose.size(), n));
  for (int j = 0; j < n; ++j)
    if (joints[j].parent < -1 || joints[j].parent >= n)
      throw std::invalid_argument(fmt::format("joint {} ({}) has parent {}, not a joint", j, joints[j].name, joints[j].parent));

  // Memoized walk up the parent links: a joint's world transform is computed once its parent's is known.
  // State 0: not started, 1: on the current chain, 2: done. Meeting a joint in state 1 again is a cycle.
  std::vector<Eigen::Affine3d> world(n, Eigen::Affine3d::Identity());
  std::vector<char> state(n, 0);
  std::vector<int> chain;
  for (int start = 0; start < n; ++start) {
    chain.clear();
    int j = start;
    while (j >= 0 && state[j] == 0) {
      state[j] = 1;
      chain.push_back(j);
      j = joints[j].parent;
    }
    if (j >= 0 && state[j] == 1)
      throw std::invalid_argument(fmt::format("the joints' parent links form a cycle through joint {} ({})", j, joints[j].name));
    // chain runs from `start` up to the first joint whose parent is known (or a root): fill it top down.
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
      const int k = *it;
      const int p = joints[k].parent;
      world[k] = p < 0 ? pose[k].matrix() : world[p] * pose[k].matrix();
      if (!world[k].matrix().allFinite())
        throw std::invalid_argument(fmt::format("the world transform of joint {} ({}) is not finite", k, joints[k].name));
      state[k] = 2;
    }
  }
  return world;
}

int Skeleton::find(std::string_view name) const {
  for (int j = 0; j < size(); ++j)
    if (joints[j].name == name) return j;
  return -1;
}

std::vector<std::vector<int>> Skeleton::children() const {
  std::vector<std::vector<int>> out(joints.size());
  for (int j = 0; j < size(); ++j) {
    const int p = joints[j].parent;
    if (p >= 0 && p < size()) out[p].push_back(j);
  }
  return out;
}

}  // namespace snh
