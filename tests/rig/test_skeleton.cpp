// Skeletons, clips and skinning on hand-made rigs: forward kinematics against positions worked out by hand,
// any joint order, cycles refused; keyframed rotations slerped at constant angular speed and held outside
// their keys; linear blend skinning as the weighted mean of the joints' rigid motions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "snh/rig/animation.hpp"
#include "snh/rig/skeleton.hpp"
#include "snh/rig/skinning.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::about;

Joint joint(const std::string& name, int parent, const Eigen::Vector3d& t, const Eigen::Quaterniond& r,
            const Eigen::Vector3d& s = Eigen::Vector3d::Ones()) {
  Joint j;
  j.name = name;
  j.parent = parent;
  j.rest.translation = t;
  j.rest.rotation = r;
  j.rest.scale = s;
  return j;
}

/// A planar arm: a shoulder 2 above the origin and two unit links, each joint turning about z.
Skeleton arm(double a0, double a1, double a2) {
  Skeleton s;
  s.joints.push_back(joint("shoulder", -1, {0, 0, 2}, about(Eigen::Vector3d::UnitZ(), a0)));
  s.joints.push_back(joint("elbow", 0, {1, 0, 0}, about(Eigen::Vector3d::UnitZ(), a1)));
  s.joints.push_back(joint("wrist", 1, {1, 0, 0}, about(Eigen::Vector3d::UnitZ(), a2)));
  return s;
}

TEST(Skeleton, ForwardKinematicsOfAPlanarChain) {
  const double a0 = 0.3, a1 = -1.1, a2 = 0.7;
  const Skeleton s = arm(a0, a1, a2);
  const auto world = s.world(s.rest_pose());
  ASSERT_EQ(world.size(), 3u);
  // Each joint sits one unit along its parent's x axis, which points at the sum of the angles above it.
  const Eigen::Vector3d elbow(std::cos(a0), std::sin(a0), 2);
  const Eigen::Vector3d wrist = elbow + Eigen::Vector3d(std::cos(a0 + a1), std::sin(a0 + a1), 0);
  const Eigen::Vector3d tip = wrist + Eigen::Vector3d(std::cos(a0 + a1 + a2), std::sin(a0 + a1 + a2), 0);
  EXPECT_LT((world[0].translation() - Eigen::Vector3d(0, 0, 2)).norm(), 1e-14);
  EXPECT_LT((world[1].translation() - elbow).norm(), 1e-14);
  EXPECT_LT((world[2].translation() - wrist).norm(), 1e-14);
  EXPECT_LT((world[2] * Eigen::Vector3d(1, 0, 0) - tip).norm(), 1e-14);
  EXPECT_LT((world[2].linear() - about(Eigen::Vector3d::UnitZ(), a0 + a1 + a2).toRotationMatrix()).norm(), 1e-14);
}

TEST(Skeleton, ScaleOfAParentStretchesItsChildren) {
  Skeleton s;
  s.joints.push_back(joint("root", -1, {0, 0, 0}, Eigen::Quaterniond::Identity(), {2, 3, 1}));
  s.joints.push_back(joint("child", 0, {1, 1, 0}, Eigen::Quaterniond::Identity()));
  const auto world = s.world(s.rest_pose());
  EXPECT_LT((world[1].translation() - Eigen::Vector3d(2, 3, 0)).norm(), 1e-15);
}

TEST(Skeleton, AnyJointOrderGivesTheSameWorldTransforms) {
  const Skeleton s = arm(0.4, 0.9, -0.2);
  const auto expected = s.world(s.rest_pose());
  // wrist, shoulder, elbow: children before their parents.
  const int order[3] = {2, 0, 1};
  int position[3];
  for (int i = 0; i < 3; ++i) position[order[i]] = i;
  Skeleton shuffled;
  for (const int j : order) {
    Joint copy = s.joints[j];
    copy.parent = copy.parent < 0 ? -1 : position[copy.parent];
    shuffled.joints.push_back(copy);
  }
  const auto world = shuffled.world(shuffled.rest_pose());
  for (int i = 0; i < 3; ++i) EXPECT_LT((world[i].matrix() - expected[order[i]].matrix()).norm(), 1e-14) << i;
  EXPECT_EQ(shuffled.find("elbow"), 2);
  EXPECT_EQ(shuffled.find("knee"), -1);
  const auto children = shuffled.children();
  EXPECT_EQ(children[1], std::vector<int>{2});  // shoulder → elbow
  EXPECT_EQ(children[2], std::vector<int>{0});  // elbow → wrist
  EXPECT_TRUE(children[0].empty());
}

TEST(Skeleton, CyclesAndBadPosesAreRefused) {
  Skeleton s = arm(0, 0, 0);
  EXPECT_THROW((void)s.world({}), std::invalid_argument);
  Pose overflow = s.rest_pose();
  overflow[1].scale.x() = 1e300;  // finite, but not once the wrist's translation is scaled by it twice
  overflow[2].scale.x() = 1e300;
  overflow[2].translation.x() = 1e300;
  EXPECT_THROW((void)s.world(overflow), std::invalid_argument);
  s.joints[0].parent = 2;  // shoulder → wrist → elbow → shoulder
  EXPECT_THROW((void)s.world(s.rest_pose()), std::invalid_argument);
  s.joints[0].parent = 0;  // its own parent
  EXPECT_THROW((void)s.world(s.rest_pose()), std::invalid_argument);
  s.joints[0].parent = 3;  // no such joint
  EXPECT_THROW((void)s.world(s.rest_pose()), std::invalid_argument);
}

TEST(Clip, KeysAreSlerpedAtConstantSpeedAndHeldOutsideThem) {
  Skeleton s = arm(0, 0, 0);
  const Eigen::Quaterniond rest = about(Eigen::Vector3d(1, 2, 3), 0.8);
  s.joints[1].rest.rotation = rest;
  const Eigen::Vector3d axis = Eigen::Vector3d(0, 1, 1).normalized();
  const double angle = 2.4;
  JointKeys k;
  k.joint = 1;
  k.times = {1.0, 3.0};
  k.rotations = {Eigen::Quaterniond::Identity(), about(axis, angle)};
  const Clip clip = clip_from_keys("bend", s, {k});
  EXPECT_EQ(clip.name, "bend");
  EXPECT_DOUBLE_EQ(clip.duration(), 3.0);
  ASSERT_EQ(clip.channels.size(), 1u);
  // The key rotates about the joint's own axes: local rotation rest · key(t), key(t) turning by angle · (t − 1)/2.
  for (const double t : {-1.0, 1.0, 1.5, 2.0, 2.75, 3.0, 10.0}) {
    const double f = std::clamp((t - 1.0) / 2.0, 0.0, 1.0);
    const Eigen::Quaterniond expected = rest * about(axis, f * angle);
    const Pose pose = sample(clip, s, t);
    EXPECT_LT(pose[1].rotation.angularDistance(expected), 1e-12) << "t = " << t;
    EXPECT_LT(std::abs(pose[1].rotation.norm() - 1.0), 1e-12);
    // The other joints and paths keep their rest values.
    EXPECT_EQ(pose[0].rotation.coeffs(), s.joints[0].rest.rotation.coeffs());
    EXPECT_EQ(pose[1].translation, s.joints[1].rest.translation);
  }
  EXPECT_THROW((void)sample(clip, s, std::nan("")), std::invalid_argument);
  k.times = {1.0, 1.0};
  EXPECT_THROW((void)clip_from_keys("bad", s, {k}), std::invalid_argument);
  k.times = {1.0, 2.0};
  k.joint = 3;
  EXPECT_THROW((void)clip_from_keys("bad", s, {k}), std::invalid_argument);
}

/// A channel of one joint of `s` from keys given as columns.
Channel channel(ChannelPath path, Interpolation interp, std::vector<double> times, Eigen::MatrixXd values) {
  Channel c;
  c.joint = 0;
  c.path = path;
  c.interpolation = interp;
  c.times = std::move(times);
  c.values = std::move(values);
  return c;
}

TEST(Clip, RotationsTakeTheShorterArc) {
  const Skeleton s = arm(0, 0, 0);
  // The second key is stored as −q: the same rotation; the slerp must not go the long way round.
  const Eigen::Quaterniond q = about(Eigen::Vector3d::UnitX(), 1.0);
  Eigen::MatrixXd v(4, 2);
  v << 0, -q.x(), 0, -q.y(), 0, -q.z(), 1, -q.w();
  Clip clip;
  clip.channels.push_back(channel(ChannelPath::rotation, Interpolation::linear, {0.0, 1.0}, v));
  const Pose pose = sample(clip, s, 0.5);
  EXPECT_LT(pose[0].rotation.angularDistance(about(Eigen::Vector3d::UnitX(), 0.5)), 1e-12);
}

TEST(Clip, StepHoldsAKeyAndCubicSplineFollowsACubic) {
  const Skeleton s = arm(0, 0, 0);
  Eigen::MatrixXd steps(3, 3);
  steps << 1, 2, 3, 0, 0, 0, 0, 0, 0;
  // A cubic spline reproduces a cubic p exactly when its tangents are p' (glTF: per second, scaled by the
  // key interval): p(t) = 1 + t − 0.5 t² + 0.25 t³ in every component.
  const auto p = [](double t) { return 1 + t - 0.5 * t * t + 0.25 * t * t * t; };
  const auto dp = [](double t) { return 1 - t + 0.75 * t * t; };
  const std::vector<double> times{0.0, 0.5, 2.0};
  Eigen::MatrixXd cubic(3, 9);
  for (int k = 0; k < 3; ++k) {
    cubic.col(3 * k).setConstant(dp(times[k]));
    cubic.col(3 * k + 1).setConstant(p(times[k]));
    cubic.col(3 * k + 2).setConstant(dp(times[k]));
  }
  Clip clip;
  clip.channels.push_back(channel(ChannelPath::translation, Interpolation::step, {0.0, 1.0, 2.0}, steps));
  clip.channels.push_back(channel(ChannelPath::scale, Interpolation::cubic_spline, times, cubic));
  EXPECT_DOUBLE_EQ(clip.duration(), 2.0);
  const std::vector<std::pair<double, double>> step_at{{-1, 1}, {0, 1}, {0.99, 1}, {1, 2}, {1.5, 2}, {2, 3}, {5, 3}};
  for (const auto& [t, x] : step_at) EXPECT_EQ(sample(clip, s, t)[0].translation.x(), x) << "t = " << t;
  for (const double t : {0.1, 0.25, 0.5, 0.9, 1.3, 1.99})
    EXPECT_NEAR(sample(clip, s, t)[0].scale.y(), p(t), 1e-13) << "t = " << t;
  EXPECT_EQ(sample(clip, s, -3)[0].scale.z(), p(0));
  EXPECT_EQ(sample(clip, s, 7)[0].scale.z(), p(2));
}

TEST(Skin, BlendIsTheMeanOfTheJointsRigidMotions) {
  RiggedModel m;
  m.skeleton.joints.push_back(joint("a", -1, {0, 0, 0}, Eigen::Quaterniond::Identity()));
  m.skeleton.joints.push_back(joint("b", -1, {0, 0, 1}, Eigen::Quaterniond::Identity()));
  for (const auto& w : m.skeleton.world(m.skeleton.rest_pose())) m.inverse_bind.push_back(w.inverse().matrix());
  m.vertices.resize(3, 3);
  m.vertices << 1, 0, 0.5,  //
      0, 2, -1,             //
      0, 1, 3;
  m.joint_index.resize(4, 3);
  m.joint_index << 0, 0, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0;
  m.joint_weight.resize(4, 3);
  m.joint_weight << 1, 0.5, 1, 0, 0.5, 0, 0, 0, 0, 0, 0, 0;
  // At rest every vertex stays put.
  EXPECT_LT((skin_vertices(m, m.skeleton.world(m.skeleton.rest_pose())) - m.vertices).norm(), 1e-14);
  // Joint a turns a quarter about z (x, y, z) → (−y, x, z); joint b moves by (2, 0, 0).
  Pose pose = m.skeleton.rest_pose();
  pose[0].rotation = about(Eigen::Vector3d::UnitZ(), std::numbers::pi / 2);
  pose[1].translation += Eigen::Vector3d(2, 0, 0);
  const Eigen::Matrix3Xd x = skin_vertices(m, m.skeleton.world(pose));
  const auto turn = [](const Eigen::Vector3d& v) { return Eigen::Vector3d(-v.y(), v.x(), v.z()); };
  const auto move = [](const Eigen::Vector3d& v) { return Eigen::Vector3d(v + Eigen::Vector3d(2, 0, 0)); };
  EXPECT_LT((x.col(0) - turn(m.vertices.col(0))).norm(), 1e-14);
  EXPECT_LT((x.col(1) - 0.5 * (turn(m.vertices.col(1)) + move(m.vertices.col(1)))).norm(), 1e-14);
  EXPECT_LT((x.col(2) - move(m.vertices.col(2))).norm(), 1e-14);
  EXPECT_THROW((void)skin_vertices(m, {}), std::invalid_argument);
}

}  // namespace
}  // namespace snh
