#pragma once
// Signed distances from points to a triangle surface, for pictures that compare two shapes of one skin (a
// flesh run's simulated surface against the same surface posed by skinning, or two runs' surfaces).
//
// |d| is the distance to the nearest point c of any triangle. Its sign is that of (p − c)·n(c), n the
// surface's smooth normal at c: each position's angle-weighted normal over every triangle that touches it
// (vertices at one position, as a UV seam splits them, count as one), interpolated over the nearest triangle.
// Positive is outside (the side the triangles' counter-clockwise normals face), negative inside; an open
// surface has the same two sides near it.
#include <vector>

#include <Eigen/Core>

#include "snh/contact/box_tree.hpp"
#include "snh/math/types.hpp"

namespace snh::contact {

/// The point of triangle (a, b, c) nearest p, as barycentric weights (wa, wb, wc) summing to 1.
[[nodiscard]] Vec3 nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

class SurfaceDistance {
 public:
  /// vertices: 3 by n; triangles: 3 by t, 0-based. Throws std::invalid_argument (one line) for an index out of
  /// range, a vertex that is not finite or no triangles.
  SurfaceDistance(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& triangles);

  /// The signed distance of p, given `bound` ≥ |d| (the distance from p to any point of the surface, such as
  /// one of its vertices): only the triangles near the ball of that radius are looked at.
  [[nodiscard]] double signed_distance(const Vec3& p, double bound) const;
  /// The same with the distance to vertex `near` as the bound.
  [[nodiscard]] double signed_distance(const Vec3& p, Eigen::Index near) const;

 private:
  Eigen::Matrix3Xd vertices_;
  Eigen::Matrix3Xi triangles_;
  Eigen::Matrix3Xd normals_;  ///< per vertex: its position's normal (unit, or zero where no triangle has area)
  BoxTree tree_;
};

}  // namespace snh::contact
