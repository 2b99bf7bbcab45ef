// Bones: segments from a joint to each child (points for leaves), default capsule radii from the surface
// around them, and the volume vertices each binds.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "snh/rig/bones.hpp"

namespace snh {
namespace {

/// root (origin) → a (1, 0, 0) → b (2, 0, 0), and root → c (0, 1, 0): two children at the root.
Skeleton fork() {
  Skeleton s;
  s.joints = {{"root", -1, {}}, {"a", 0, {}}, {"b", 1, {}}, {"c", 0, {}}};
  s.joints[1].rest.translation = {1, 0, 0};
  s.joints[2].rest.translation = {1, 0, 0};
  s.joints[3].rest.translation = {0, 1, 0};
  return s;
}

TEST(Bones, OneSegmentPerChildAndAPointPerLeaf) {
  const Skeleton s = fork();
  const std::vector<Bone> bones = bones_of(s, s.world(s.rest_pose()));
  ASSERT_EQ(bones.size(), 5u);  // root>a, root>c, a>b, and the leaves b and c as points
  EXPECT_EQ(bones[0].name, "root>a");
  EXPECT_EQ(bones[1].name, "root>c");
  EXPECT_EQ(bones[2].name, "a>b");
  EXPECT_EQ(bones[3].name, "b");
  EXPECT_EQ(bones[3].child, -1);
  EXPECT_TRUE(bones[3].a.isApprox(Eigen::Vector3d(2, 0, 0)));
  EXPECT_TRUE(bones[3].b.isApprox(bones[3].a));
  EXPECT_EQ(bones[4].name, "c");
  EXPECT_TRUE(bones[4].a.isApprox(Eigen::Vector3d(0, 1, 0)));
}

TEST(Bones, SegmentDistance) {
  const Eigen::Vector3d a(0, 0, 0), b(2, 0, 0);
  EXPECT_DOUBLE_EQ(segment_distance(a, b, {1, 3, 4}), 5.0);   // beside the segment
  EXPECT_DOUBLE_EQ(segment_distance(a, b, {-3, 4, 0}), 5.0);  // beyond a
  EXPECT_DOUBLE_EQ(segment_distance(a, b, {5, 0, 4}), 5.0);   // beyond b
  EXPECT_DOUBLE_EQ(segment_distance(a, a, {0, 3, 4}), 5.0);   // a point
}

TEST(Bones, DefaultRadiusIsHalfTheMeanDistanceToTheSurfaceAround) {
  // A tube of radius 0.4 around the segment (0,0,0)–(2,0,0): every surface vertex is 0.4 from it.
  Bone bone{.name = "arm", .joint = 0, .child = 1, .a = {0, 0, 0}, .b = {2, 0, 0}};
  Bone far{.name = "far", .joint = 1, .child = -1, .a = {10, 0, 0}, .b = {10, 0, 0}};
  Eigen::Matrix3Xd surface(3, 40);
  for (int i = 0; i < 40; ++i) {
    const double angle = 2.0 * std::numbers::pi * (i % 8) / 8.0;
    surface.col(i) = Eigen::Vector3d(0.2 + 1.6 * (i / 8) / 4.0, 0.4 * std::cos(angle), 0.4 * std::sin(angle));
  }
  const std::vector<double> r = default_radii({bone, far}, surface);
  EXPECT_NEAR(r[0], 0.2, 1e-12);
  // No surface vertex is nearest to "far": half the distance to the nearest one (at x = 1.8).
  EXPECT_NEAR(r[1], 0.5 * std::hypot(10.0 - 1.8, 0.4), 1e-12);
}

TEST(Bones, BindingTakesTheDeepestCapsule) {
  std::vector<Bone> bones{{.name = "x", .joint = 0, .child = 1, .a = {0, 0, 0}, .b = {1, 0, 0}, .radius = 0.3},
                          {.name = "y", .joint = 0, .child = 2, .a = {0, 0, 0}, .b = {0, 1, 0}, .radius = 0.3}};
  Eigen::Matrix3Xd X(3, 4);
  X.col(0) = Eigen::Vector3d(0.5, 0.1, 0);   // inside x only
  X.col(1) = Eigen::Vector3d(0.1, 0.2, 0);   // inside both: 0.2 from x, 0.1 from y, so deeper in y
  X.col(2) = Eigen::Vector3d(0.05, 0.6, 0);  // inside y only
  X.col(3) = Eigen::Vector3d(0.5, 0.5, 0);   // in neither
  const Binding b = bind_to_bones(bones, X);
  EXPECT_EQ(b.vertex, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(b.bone, (std::vector<int>{0, 1, 1}));
  EXPECT_EQ(b.count_per_bone(2), (std::vector<int>{1, 2}));
  X.col(1) = Eigen::Vector3d(0.2, 0.05, 0);  // 0.05 from x, 0.2 from y
  const Binding c = bind_to_bones(bones, X);
  EXPECT_EQ(c.bone[1], 0);
}

TEST(Bones, SoftBindingTakesTheShellOutsideTheCapsulesWithFadingWeights) {
  std::vector<Bone> bones{{.name = "x", .joint = 0, .child = 1, .a = {0, 0, 0}, .b = {1, 0, 0}, .radius = 0.3},
                          {.name = "y", .joint = 0, .child = 2, .a = {0, 0, 0}, .b = {0, 1, 0}, .radius = 0.2}};
  Eigen::Matrix3Xd X(3, 6);
  X.col(0) = Eigen::Vector3d(0.5, 0.1, 0);   // inside x: hard
  X.col(1) = Eigen::Vector3d(0.5, 0.35, 0);  // 0.05 outside x, 0.3 outside y: soft to x, weight 0.75
  X.col(2) = Eigen::Vector3d(0.5, 0.45, 0);  // 0.15 outside x, 0.3 outside y: soft to x, weight 0.25
  X.col(3) = Eigen::Vector3d(0.5, 0.5, 0);   // 0.2 outside x: on the shell's outer edge, not bound
  X.col(4) = Eigen::Vector3d(0.25, 0.8, 0);  // 0.5 outside x, 0.05 outside y: soft to y
  X.col(5) = Eigen::Vector3d(3, 3, 3);       // far from both
  const Binding hard = bind_to_bones(bones, X);
  EXPECT_EQ(hard.vertex, (std::vector<int>{0}));
  const SoftBinding soft = soft_bind_to_bones(bones, X, 0.2, hard);
  EXPECT_EQ(soft.vertex, (std::vector<int>{1, 2, 4}));
  EXPECT_EQ(soft.bone, (std::vector<int>{0, 0, 1}));
  ASSERT_EQ(soft.weight.size(), 3u);
  EXPECT_NEAR(soft.weight[0], 1.0 - 0.05 / 0.2, 1e-12);
  EXPECT_NEAR(soft.weight[1], 1.0 - 0.15 / 0.2, 1e-12);
  EXPECT_NEAR(soft.weight[2], 1.0 - 0.05 / 0.2, 1e-12);
  EXPECT_TRUE(soft_bind_to_bones(bones, X, 0.0, hard).vertex.empty()) << "no shell, no soft binding";
  // A vertex held hard is never bound softly too.
  const SoftBinding all = soft_bind_to_bones(bones, X, 10.0, hard);
  EXPECT_EQ(all.vertex, (std::vector<int>{1, 2, 3, 4, 5}));
}

TEST(Bones, SplitAtJointsReleasesTheVerticesOfCellsHeldByTwoJoints) {
  // Three tets in a row sharing faces: vertices 0..5; bones of joints 0 and 1 (and a second bone of joint 0).
  std::vector<Bone> bones{{.name = "a", .joint = 0}, {.name = "b", .joint = 1}, {.name = "c", .joint = 0}};
  Eigen::MatrixXi cells(4, 3);
  cells << 0, 1, 2, 1, 2, 3, 2, 3, 4, 3, 4, 5;  // columns: {0,1,2,3}, {1,2,3,4}, {2,3,4,5}
  Binding b;
  b.vertex = {0, 1, 4, 5};
  b.bone = {0, 2, 1, 1};  // 0 and 1 with joint 0 (two bones of it), 4 and 5 with joint 1
  const JointSplit split = split_at_joints(b, bones, cells, 6);
  // Cell {1,2,3,4} holds 1 (joint 0) and 4 (joint 1): both released; cell {0,1,2,3} holds joint 0 only.
  EXPECT_EQ(split.kept.vertex, (std::vector<int>{0, 5}));
  EXPECT_EQ(split.kept.bone, (std::vector<int>{0, 1}));
  EXPECT_EQ(split.released.vertex, (std::vector<int>{1, 4}));
  EXPECT_EQ(split.released.bone, (std::vector<int>{2, 1}));
  // Two bones of one joint never conflict.
  b.bone = {0, 2, 0, 2};
  EXPECT_TRUE(split_at_joints(b, bones, cells, 6).released.vertex.empty());
  // Released vertices join a soft binding at weight 1, in vertex order; a vertex already soft keeps its weight.
  SoftBinding soft;
  soft.vertex = {2, 4};
  soft.bone = {0, 0};
  soft.weight = {0.5, 0.25};
  const SoftBinding merged = merge_soft(soft, split.released, 1.0);
  EXPECT_EQ(merged.vertex, (std::vector<int>{1, 2, 4}));
  EXPECT_EQ(merged.bone, (std::vector<int>{2, 0, 0}));
  EXPECT_EQ(merged.weight, (std::vector<double>{1.0, 0.5, 0.25}));
}

}  // namespace
}  // namespace snh
