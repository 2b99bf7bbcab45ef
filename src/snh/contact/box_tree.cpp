#include "snh/contact/box_tree.hpp"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <stdexcept>
#include <string>

namespace snh::contact {

namespace {

/// The bits of v (< 2^21) spread to every third bit.
std::uint64_t spread(std::uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

}  // namespace

BoxTree::BoxTree(const Eigen::Matrix3Xd& lo, const Eigen::Matrix3Xd& hi) {
  if (lo.cols() != hi.cols())
    throw std::invalid_argument("box tree: " + std::to_string(lo.cols()) + " low corners, " + std::to_string(hi.cols()) + " high");
  if (!lo.allFinite() || !hi.allFinite()) throw std::invalid_argument("box tree: a box corner is not finite");
  const Eigen::Index n = lo.cols();
  if (n == 0) return;
  // The boxes in the order of their centres along a Z-order curve (21 bits an axis over the centres' box), so
  // that boxes next to each other in that order are near each other in space.
  Eigen::Vector3d c_lo = 0.5 * (lo.col(0) + hi.col(0)), c_hi = c_lo;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector3d c = 0.5 * (lo.col(i) + hi.col(i));
    c_lo = c_lo.cwiseMin(c);
    c_hi = c_hi.cwiseMax(c);
  }
  const Eigen::Vector3d scale = ((1 << 21) - 1) / (c_hi - c_lo).cwiseMax(Eigen::Vector3d::Constant(1e-300)).array();
  std::vector<std::pair<std::uint64_t, int>> keyed(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector3d q = (0.5 * (lo.col(i) + hi.col(i)) - c_lo).array() * scale.array();
    if (!q.allFinite()) q.setZero();  // (centres spread past the largest double: any order is correct)
    q = q.cwiseMax(0.0).cwiseMin((1 << 21) - 1);
    keyed[static_cast<std::size_t>(i)] = {spread(static_cast<std::uint64_t>(q.x())) | spread(static_cast<std::uint64_t>(q.y())) << 1 |
                                              spread(static_cast<std::uint64_t>(q.z())) << 2,
                                          static_cast<int>(i)};
  }
  std::sort(keyed.begin(), keyed.end());
  order_.resize(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) order_[i] = keyed[i].second;
  // Leaves of kLeafSize consecutive boxes, then each level's nodes paired in order (an odd last one goes up
  // as it is) until one is left: the root, the last node.
  nodes_.reserve(2 * order_.size() / kLeafSize + 64);
  for (int begin = 0; begin < size(); begin += kLeafSize) {
    Node leaf;
    leaf.begin = begin;
    leaf.end = std::min(begin + kLeafSize, size());
    leaf.lo = lo.col(order_[static_cast<std::size_t>(begin)]);
    leaf.hi = hi.col(order_[static_cast<std::size_t>(begin)]);
    for (int i = begin; i < leaf.end; ++i) {
      leaf.lo = leaf.lo.cwiseMin(lo.col(order_[static_cast<std::size_t>(i)]));
      leaf.hi = leaf.hi.cwiseMax(hi.col(order_[static_cast<std::size_t>(i)]));
    }
    nodes_.push_back(leaf);
  }
  std::size_t level = 0, count = nodes_.size();  // the current level: nodes_[level, level + count)
  while (count > 1) {
    const std::size_t next = nodes_.size();
    for (std::size_t i = 0; i < count; i += 2) {
      if (i + 1 == count) {
        nodes_.push_back(nodes_[level + i]);
        continue;
      }
      const Node& a = nodes_[level + i];
      const Node& b = nodes_[level + i + 1];
      Node parent;
      parent.lo = a.lo.cwiseMin(b.lo);
      parent.hi = a.hi.cwiseMax(b.hi);
      parent.begin = a.begin;
      parent.end = b.end;
      parent.left = static_cast<int>(level + i);
      nodes_.push_back(parent);
    }
    level = next;
    count = nodes_.size() - next;
  }
}

std::vector<int> BoxTree::near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  std::vector<int> out;
  if (nodes_.empty()) return out;
  std::vector<int> stack{static_cast<int>(nodes_.size()) - 1};  // the root
  while (!stack.empty()) {
    const Node& n = nodes_[static_cast<std::size_t>(stack.back())];
    stack.pop_back();
    if (!((n.lo.array() <= hi.array()).all() && (lo.array() <= n.hi.array()).all())) continue;
    if (n.left < 0) {
      out.insert(out.end(), order_.begin() + n.begin, order_.begin() + n.end);
      continue;
    }
    stack.push_back(n.left + 1);
    stack.push_back(n.left);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace snh::contact
