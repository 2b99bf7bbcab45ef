#pragma once
// A union-find over 0 .. n − 1 (path halving; the smaller index is a group's root, so roots come out in
// index order): connected parts of meshes, lattices and models.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace snh {

class UnionFind {
 public:
  explicit UnionFind(std::size_t n) : parent_(n) {
    for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<int>(i);
  }
  /// The root of i's group: its smallest member.
  int root(int i) {
    while (parent_[static_cast<std::size_t>(i)] != i)
      i = parent_[static_cast<std::size_t>(i)] = parent_[static_cast<std::size_t>(parent_[static_cast<std::size_t>(i)])];
    return i;
  }
  void join(int a, int b) {
    a = root(a), b = root(b);
    if (a != b) parent_[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  }

 private:
  std::vector<int> parent_;
};

}  // namespace snh
