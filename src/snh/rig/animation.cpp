#include "snh/rig/animation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace snh {
namespace {

Eigen::Quaterniond quaternion_of(const Eigen::Vector4d& xyzw) { return {xyzw(3), xyzw(0), xyzw(1), xyzw(2)}; }

/// A unit quaternion, or invalid_argument for one of zero length.
Eigen::Quaterniond unit(const Eigen::Quaterniond& q, int joint) {
  const double n = q.norm();
  if (!(n > 0.0) || !std::isfinite(n))
    throw std::invalid_argument(fmt::format("a rotation of joint {} is not a rotation (length {})", joint, n));
  return Eigen::Quaterniond(q.coeffs() / n);
}

/// The key column of key k: for cubic_spline the value sits between its in- and out-tangents.
Eigen::VectorXd key_value(const Channel& c, std::size_t k) {
  const auto col = static_cast<Eigen::Index>(c.interpolation == Interpolation::cubic_spline ? 3 * k + 1 : k);
  return c.values.col(col);
}

/// The channel's value at t (3 entries, or 4 for a rotation x, y, z, w).
Eigen::VectorXd evaluate(const Channel& c, double t) {
  const std::size_t n = c.times.size();
  if (t <= c.times.front()) return key_value(c, 0);
  if (t >= c.times.back()) return key_value(c, n - 1);
  // times[k] <= t < times[k + 1]
  const std::size_t k = static_cast<std::size_t>(std::upper_bound(c.times.begin(), c.times.end(), t) - c.times.begin()) - 1;
  const double t0 = c.times[k], t1 = c.times[k + 1], td = t1 - t0;
  const double s = (t - t0) / td;
  const bool rotation = c.path == ChannelPath::rotation;
  switch (c.interpolation) {
    case Interpolation::step:
      return key_value(c, k);
    case Interpolation::linear: {
      const Eigen::VectorXd p0 = key_value(c, k), p1 = key_value(c, k + 1);
      if (!rotation) return (1.0 - s) * p0 + s * p1;
      // Eigen's slerp takes the shorter arc (it negates one end when their dot product is negative).
      const Eigen::Quaterniond q = unit(quaternion_of(p0), c.joint).slerp(s, unit(quaternion_of(p1), c.joint));
      return q.coeffs();  // x, y, z, w
    }
    case Interpolation::cubic_spline: {
      // glTF 2.0 Appendix C: Hermite spline with the tangents scaled by the key interval.
      const auto col = [&](std::size_t i) { return Eigen::VectorXd(c.values.col(static_cast<Eigen::Index>(i))); };
      const Eigen::VectorXd p0 = col(3 * k + 1), b0 = col(3 * k + 2), a1 = col(3 * (k + 1)), p1 = col(3 * (k + 1) + 1);
      const double s2 = s * s, s3 = s2 * s;
      const Eigen::VectorXd v = (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * td * b0 + (-2 * s3 + 3 * s2) * p1 +
                                (s3 - s2) * td * a1;
      if (!rotation) return v;
      return unit(quaternion_of(v), c.joint).coeffs();
    }
  }
  return key_value(c, k);
}

void check_channel(const Channel& c, int joints) {
  if (c.joint < 0 || c.joint >= joints)
    throw std::invalid_argument(fmt::format("a channel animates joint {}, but the skeleton has {} joints", c.joint, joints));
  const Eigen::Index rows = c.path == ChannelPath::rotation ? 4 : 3;
  const auto per_key = static_cast<std::size_t>(c.interpolation == Interpolation::cubic_spline ? 3 : 1);
  if (c.values.rows() != rows || static_cast<std::size_t>(c.values.cols()) != per_key * c.times.size())
    throw std::invalid_argument(fmt::format("a channel of joint {} has {} keys but a {} by {} value matrix", c.joint,
                                            c.times.size(), c.values.rows(), c.values.cols()));
}

}  // namespace

double Clip::duration() const {
  double d = 0.0;
  for (const Channel& c : channels)
    if (!c.times.empty()) d = std::max(d, c.times.back());
  return d;
}

bool Clip::moves() const {
  for (const Channel& c : channels)
    for (Eigen::Index k = 1; k < c.values.cols(); ++k)
      if (c.values.col(k) != c.values.col(0)) return true;
  return false;
}

Pose sample(const Clip& clip, const Skeleton& skeleton, double t) {
  if (std::isnan(t)) throw std::invalid_argument(fmt::format("clip {}: sampled at a time that is not a number", clip.name));
  Pose pose = skeleton.rest_pose();
  for (const Channel& c : clip.channels) {
    check_channel(c, skeleton.size());
    if (c.times.empty()) continue;
    const Eigen::VectorXd v = evaluate(c, t);
    Transform& local = pose[static_cast<std::size_t>(c.joint)];
    switch (c.path) {
      case ChannelPath::translation: local.translation = v.head<3>(); break;
      case ChannelPath::scale: local.scale = v.head<3>(); break;
      case ChannelPath::rotation: local.rotation = unit(quaternion_of(v.head<4>()), c.joint); break;
    }
  }
  return pose;
}

Clip clip_from_keys(const std::string& name, const Skeleton& skeleton, const std::vector<JointKeys>& keys) {
  Clip clip;
  clip.name = name;
  for (const JointKeys& k : keys) {
    if (k.joint < 0 || k.joint >= skeleton.size())
      throw std::invalid_argument(fmt::format("clip {}: keys for joint {}, but the skeleton has {} joints", name, k.joint,
                                              skeleton.size()));
    if (k.times.empty() || k.times.size() != k.rotations.size())
      throw std::invalid_argument(fmt::format("clip {}: joint {} has {} key times and {} rotations", name,
                                              skeleton.joints[k.joint].name, k.times.size(), k.rotations.size()));
    for (std::size_t i = 0; i < k.times.size(); ++i)
      if (!std::isfinite(k.times[i]) || (i > 0 && !(k.times[i] > k.times[i - 1])))
        throw std::invalid_argument(fmt::format("clip {}: the key times of joint {} are not finite and strictly increasing",
                                                name, skeleton.joints[k.joint].name));
    Channel c;
    c.joint = k.joint;
    c.path = ChannelPath::rotation;
    c.interpolation = Interpolation::linear;
    c.times = k.times;
    c.values.resize(4, static_cast<Eigen::Index>(k.times.size()));
    const Eigen::Quaterniond rest = unit(skeleton.joints[k.joint].rest.rotation, k.joint);
    for (std::size_t i = 0; i < k.rotations.size(); ++i)
    {
      const Eigen::Vector4d q = unit(rest * unit(k.rotations[i], k.joint), k.joint).coeffs();
      // x, y, z, w, element by element (GCC 12 wrongly warns of AVX-512 loads past q otherwise)
      for (Eigen::Index r = 0; r < 4; ++r) c.values(r, static_cast<Eigen::Index>(i)) = q(r);
    }
    clip.channels.push_back(std::move(c));
  }
  return clip;
}

}  // namespace snh
