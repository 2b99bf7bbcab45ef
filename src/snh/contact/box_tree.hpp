#pragma once
// A tree of axis-aligned boxes built once (a bounding volume hierarchy), answering which of them may overlap
// a query box at a cost in proportion to the answer and the tree's depth, not to the number of boxes. A
// static mesh collider keeps one over its triangles, so the broad phase of a body against a collider of
// millions of triangles looks only at those near the body.
//
// Built bottom up: the boxes are sorted along a Z-order (Morton) curve through their centres, taken
// kLeafSize at a time as leaves, and the nodes of each level paired in that order up to the root. Each node
// keeps the box of its boxes; the boxes themselves are not kept, so a query returns every box of each leaf whose node box overlaps the query (a
// superset of the overlapping boxes, the caller tests each exactly), sorted by id.
#include <vector>

#include <Eigen/Core>

namespace snh::contact {

class BoxTree {
 public:
  static constexpr int kLeafSize = 4;

  BoxTree() = default;
  /// The boxes [lo.col(i), hi.col(i)], i in [0, n). Throws std::invalid_argument (one line) for sizes
  /// that differ or a corner that is not finite.
  BoxTree(const Eigen::Matrix3Xd& lo, const Eigen::Matrix3Xd& hi);

  /// The ids of the boxes of every leaf whose node box overlaps [lo, hi] (touching counts): every box that
  /// overlaps it and some near it, ascending, each once.
  [[nodiscard]] std::vector<int> near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;

  [[nodiscard]] int size() const { return static_cast<int>(order_.size()); }

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    int begin = 0, end = 0;  ///< its boxes: order_[begin, end)
    int left = -1;           ///< children left, left + 1; −1: a leaf
  };
  std::vector<Node> nodes_;  ///< leaves first, then each level's parents; the root last
  std::vector<int> order_;
};

}  // namespace snh::contact
