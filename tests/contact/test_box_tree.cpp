// The box tree against a brute-force list of the boxes that overlap a query: never one missed, each once, in
// increasing order; a query far from every box gets none, a small one a small share of them.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "snh/contact/box_tree.hpp"

namespace snh::contact {
namespace {

TEST(BoxTree, ReturnsEveryOverlappingBoxOnceInOrder) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1), size(0, 0.01);
  const int n = 20000;
  Eigen::Matrix3Xd lo(3, n), hi(3, n);
  for (int i = 0; i < n; ++i) {
    lo.col(i) << u(rng), u(rng), 0.2 * u(rng);  // flat: a floor's triangles
    hi.col(i) = lo.col(i) + Eigen::Vector3d(size(rng), size(rng), size(rng));
  }
  lo.col(17) = hi.col(17) = Eigen::Vector3d(0.5, 0.5, 0.1);  // a point
  const BoxTree tree(lo, hi);
  EXPECT_EQ(tree.size(), n);
  std::size_t most = 0;
  for (int q = 0; q < 200; ++q) {
    Eigen::Vector3d a(u(rng), u(rng), 0.2 * u(rng)), b = a + Eigen::Vector3d(0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng));
    if (q == 0) a = b = Eigen::Vector3d(0.5, 0.5, 0.1);  // touching the point box
    const std::vector<int> got = tree.near(a, b);
    EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
    EXPECT_EQ(std::adjacent_find(got.begin(), got.end()), got.end());
    for (int i = 0; i < n; ++i)
      if ((lo.col(i).array() <= b.array()).all() && (a.array() <= hi.col(i).array()).all()) {
        EXPECT_TRUE(std::binary_search(got.begin(), got.end(), i)) << "query " << q << " box " << i;
      }
    most = std::max(most, got.size());
  }
  EXPECT_LT(most, static_cast<std::size_t>(n / 20));  // a tree that never split would give all of them
  EXPECT_TRUE(tree.near(Eigen::Vector3d(3, 3, 3), Eigen::Vector3d(4, 4, 4)).empty());
  EXPECT_EQ(tree.near(Eigen::Vector3d::Constant(-1), Eigen::Vector3d::Constant(2)).size(), static_cast<std::size_t>(n));
}

TEST(BoxTree, EmptyAndBadInput) {
  const BoxTree empty(Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xd(3, 0));
  EXPECT_TRUE(empty.near(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()).empty());
  Eigen::Matrix3Xd lo = Eigen::Matrix3Xd::Zero(3, 2), hi = Eigen::Matrix3Xd::Ones(3, 2);
  EXPECT_THROW(BoxTree(lo, hi.leftCols(1)), std::invalid_argument);
  hi(1, 1) = std::numeric_limits<double>::infinity();
  EXPECT_THROW(BoxTree(lo, hi), std::invalid_argument);
}

}  // namespace
}  // namespace snh::contact
