#pragma once
// Inside tests and volumes of closed triangle surfaces (DESIGN.md embed/): the generalized winding number
// (Jacobson, Kavan, Sorkine-Hornung 2013: the solid angles of the triangles seen from a point, over 4π),
// which is 1 inside a closed outward surface, 0 outside, and degrades gracefully on imperfect ones.
#include <Eigen/Core>

namespace snh {

/// The winding number of the surface (V, F) at point p: Σ solid angle / 4π.
///   V  3 by #V vertices;  F  3 by #F triangles, counter-clockwise seen from outside
[[nodiscard]] double winding_number(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, const Eigen::Vector3d& p);

/// The volume enclosed by a closed, outward-oriented surface (divergence theorem: Σ det[a, b, c] / 6).
[[nodiscard]] double enclosed_volume(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F);

}  // namespace snh
