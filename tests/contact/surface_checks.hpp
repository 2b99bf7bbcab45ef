#pragma once
// Checks of a whole triangle surface for the contact tests (tests only): whether two of its triangles
// intersect, and its smallest vertex–triangle or edge–edge distance, each over every pair of triangles that
// share no vertex (brute force, written here independently of the contact code it checks).
#include <algorithm>
#include <array>
#include <cmath>

#include <Eigen/Core>

#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/math/types.hpp"

namespace snh {

// ---- an intersection test of our own: orientation signs, conservative (a sign too close to call counts as
// zero, which can only report touching where there is none, never miss a crossing).

inline int orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 u = b - a, v = c - a, w = d - a;
  const double det = u.dot(v.cross(w));
  const double bound = 1e-12 * u.norm() * v.norm() * w.norm();
  return det > bound ? 1 : det < -bound ? -1 : 0;
}

/// Does segment pq touch triangle abc (up to the filter above)?
inline bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if (sp != 0 && sp == sq) return false;  // both strictly on one side
  const int s0 = orient(p, q, a, b), s1 = orient(p, q, b, c), s2 = orient(p, q, c, a);
  const bool has_pos = s0 > 0 || s1 > 0 || s2 > 0, has_neg = s0 < 0 || s1 < 0 || s2 < 0;
  return !(has_pos && has_neg);  // the line through pq passes inside (or on the rim of) abc
}

inline bool triangles_intersect(const std::array<Vec3, 3>& s, const std::array<Vec3, 3>& t) {
  for (int i = 0; i < 3; ++i) {
    if (segment_hits_triangle(s[i], s[(i + 1) % 3], t[0], t[1], t[2])) return true;
    if (segment_hits_triangle(t[i], t[(i + 1) % 3], s[0], s[1], s[2])) return true;
  }
  return false;
}

/// True if two triangles of F that share no vertex intersect at x (every pair checked; pairs whose bounding
/// boxes are disjoint cannot meet and are skipped).
inline bool surface_intersects(const Eigen::Matrix3Xi& F, const Eigen::Matrix3Xd& V) {
  Eigen::Matrix3Xd lo(3, F.cols()), hi(3, F.cols());
  for (Eigen::Index i = 0; i < F.cols(); ++i) {
    lo.col(i) = V.col(F(0, i)).cwiseMin(V.col(F(1, i))).cwiseMin(V.col(F(2, i)));
    hi.col(i) = V.col(F(0, i)).cwiseMax(V.col(F(1, i))).cwiseMax(V.col(F(2, i)));
  }
  for (Eigen::Index i = 0; i < F.cols(); ++i)
    for (Eigen::Index j = i + 1; j < F.cols(); ++j) {
      if ((hi.col(i).array() < lo.col(j).array()).any() || (hi.col(j).array() < lo.col(i).array()).any()) continue;
      bool shared = false;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) shared = shared || F(a, i) == F(b, j);
      if (shared) continue;
      if (triangles_intersect({V.col(F(0, i)), V.col(F(1, i)), V.col(F(2, i))},
                              {V.col(F(0, j)), V.col(F(1, j)), V.col(F(2, j))}))
        return true;
    }
  return false;
}

/// The smallest distance between a vertex and a triangle, or two edges, of F that share no vertex.
inline double surface_min_distance(const Eigen::Matrix3Xi& F, const Eigen::Matrix3Xd& V) {
  double s = INFINITY;
  for (Eigen::Index i = 0; i < F.cols(); ++i)
    for (Eigen::Index j = 0; j < F.cols(); ++j) {
      if (i == j) continue;
      for (int a = 0; a < 3; ++a) {
        const int v = F(a, i);
        if (v != F(0, j) && v != F(1, j) && v != F(2, j))
          s = std::min(s, contact::point_triangle_distance(V.col(v), V.col(F(0, j)), V.col(F(1, j)), V.col(F(2, j))));
        for (int b = 0; b < 3; ++b) {
          const int a0 = F(a, i), a1 = F((a + 1) % 3, i), b0 = F(b, j), b1 = F((b + 1) % 3, j);
          if (a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1) continue;
          s = std::min(s, contact::edge_edge_distance(V.col(a0), V.col(a1), V.col(b0), V.col(b1)));
        }
      }
    }
  return std::sqrt(s);
}

}  // namespace snh
