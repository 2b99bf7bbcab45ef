#pragma once
// Kinematic vertices (docs/design.md): sets of vertices whose held coordinates follow targets given by a
// provider, a function of time. Scripted motion (scene pins) is one provider; the stretch test's pulled
// layers another; bones (a rig's skinned capsules) are the next. The simulation only asks a provider
// where its vertices are at time t.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace snh {

/// Where a kinematic set's vertices are at time t.
class KinematicProvider {
 public:
  virtual ~KinematicProvider() = default;
  /// Overwrites `out` (3 by the set's vertex count, in the set's order) with the targets at time t.
  virtual void targets(double t, Eigen::Matrix3Xd& out) const = 0;
};

struct KinematicSet {
  std::string name;                         ///< for messages ("pins[0]")
  std::vector<int> vertices;                ///< mesh vertex indices
  std::array<bool, 3> axes{true, true, true};  ///< the coordinates held (x, y, z); the others move freely
  std::shared_ptr<const KinematicProvider> provider;
};

/// A motion of a scripted set, applied with progress p = clamp((t − start)/(end − start), 0, 1).
struct Translate {
  Eigen::Vector3d by = Eigen::Vector3d::Zero();
  double start = 0.0, end = 0.0;
};
struct Rotate {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  ///< unit
  double radians = 0.0;
  std::optional<Eigen::Vector3d> center;            ///< default: the set's centroid when the motion applies
  double start = 0.0, end = 0.0;
};
struct Scale {
  Eigen::Vector3d factors = Eigen::Vector3d::Ones();
  std::optional<Eigen::Vector3d> center;            ///< default: the set's centroid when the motion applies
  double start = 0.0, end = 0.0;
};
using Motion = std::variant<Translate, Rotate, Scale>;

/// The map the motions make of space at time t, composed in order as ScriptedMotion moves its points: a
/// rotation or scale without a centre turns about the moving centroid of base points whose centroid is
/// `centroid` (so applying it to those points gives ScriptedMotion's targets). Rotations and translations
/// only (and scales with equal factors) give a similarity.
[[nodiscard]] Eigen::Affine3d motion_transform(const std::vector<Motion>& motions, const Eigen::Vector3d& centroid, double t);

/// Base positions moved by each motion in turn.
class ScriptedMotion final : public KinematicProvider {
 public:
  ///   base     3 by n, the set's positions at t = 0
  ///   motions  composed in order
  ScriptedMotion(Eigen::Matrix3Xd base, std::vector<Motion> motions) : base_(std::move(base)), motions_(std::move(motions)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override;

 private:
  Eigen::Matrix3Xd base_;
  std::vector<Motion> motions_;
};

}  // namespace snh
