#pragma once
// Inside tests and volumes of closed triangle surfaces (docs/design.md): the generalized winding number
// (Jacobson, Kavan, Sorkine-Hornung 2013: the solid angles of the triangles seen from a point, over 4π),
// which is 1 inside a closed outward surface, 0 outside, and degrades gracefully on imperfect ones.
#include <Eigen/Core>

namespace snh {

/// The winding number of the surface (V, F) at point p: Σ solid angle / 4π, each triangle's solid angle by
/// Van Oosterom and Strackee (1983). A triangle whose plane holds p is seen edge-on (solid angle 0), so a
/// point inside a flat face gets ½. Throws std::invalid_argument for a non-finite p or V or an index out of
/// range; no triangles give 0.
///   V  3 by #V vertices;  F  3 by #F triangles, counter-clockwise seen from outside
[[nodiscard]] double winding_number(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, const Eigen::Vector3d& p);

/// The volume enclosed by a closed, outward-oriented surface (divergence theorem: Σ det[a, b, c] / 6, the
/// corners taken relative to the bounding box's centre); negative for an inward surface. Throws as
/// winding_number.
[[nodiscard]] double enclosed_volume(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F);

/// Throws std::invalid_argument unless every vertex is finite and every index of F names a vertex (the
/// message names the first vertex or triangle at fault).
void check_triangles(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F);

}  // namespace snh
