#pragma once
// Animation clips (docs/design.md): glTF 2.0 channels (translation, rotation, scale of a joint; LINEAR,
// STEP or CUBICSPLINE between keys; rotations slerped), sampled into a pose; and the keyframed joint
// rotations of a scene file, which become a clip.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "snh/rig/skeleton.hpp"

namespace snh {

enum class Interpolation { linear, step, cubic_spline };
enum class ChannelPath { translation, rotation, scale };

struct Channel {
  int joint = 0;
  ChannelPath path = ChannelPath::rotation;
  Interpolation interpolation = Interpolation::linear;
  std::vector<double> times;  ///< strictly increasing, seconds
  /// One column per key (rows 3, or 4 for a rotation quaternion stored x, y, z, w as glTF does); for
  /// cubic_spline three columns per key: in-tangent, value, out-tangent (glTF 2.0 Appendix C).
  Eigen::MatrixXd values;
};

struct Clip {
  std::string name;
  std::vector<Channel> channels;
  /// The last key's time over all channels (0 for no keys).
  [[nodiscard]] double duration() const;
  /// Some channel's keys differ from each other (a clip of one pose, such as a "bind" clip, does not move).
  [[nodiscard]] bool moves() const;
};

/// The pose of `skeleton` at time t: the rest pose with every channel's value at t in place of the path it
/// animates. Before the first key a channel holds its first value, after the last its last.
/// LINEAR rotations are slerped (shortest arc); CUBICSPLINE rotations are normalized.
[[nodiscard]] Pose sample(const Clip& clip, const Skeleton& skeleton, double t);

/// Keyframed rotations of one joint, relative to its rest rotation: at each time the joint's local rotation
/// is rest · key (the key rotates about the joint's own axes).
struct JointKeys {
  int joint = 0;
  std::vector<double> times;                 ///< strictly increasing
  std::vector<Eigen::Quaterniond> rotations; ///< one per time, unit
};

/// A clip of LINEAR rotation channels (slerp) from keyframes added to the skeleton's rest pose.
[[nodiscard]] Clip clip_from_keys(const std::string& name, const Skeleton& skeleton, const std::vector<JointKeys>& keys);

}  // namespace snh
