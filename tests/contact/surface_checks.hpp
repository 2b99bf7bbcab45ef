#pragma once
// Checks of a whole triangle surface for the contact tests (tests only): whether two of its triangles
// intersect, and its smallest vertex–triangle or edge–edge distance, each over every pair of triangles that
// share no vertex (brute force, written here independently of the contact code it checks); and a closed box
// surface for colliders.
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

// In the plane of a triangle (coordinates `u`, `v` of the two axes its normal is smallest along): the same
// filtered orientation in 2D, a point in (or on) a triangle, two segments touching.
inline int orient2(const Vec3& a, const Vec3& b, const Vec3& c, int u, int v) {
  const double det = (b[u] - a[u]) * (c[v] - a[v]) - (b[v] - a[v]) * (c[u] - a[u]);
  const double bound = 1e-12 * std::hypot(b[u] - a[u], b[v] - a[v]) * std::hypot(c[u] - a[u], c[v] - a[v]);
  return det > bound ? 1 : det < -bound ? -1 : 0;
}

inline bool segments2_touch(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, int u, int v) {
  const int o1 = orient2(p, q, a, u, v), o2 = orient2(p, q, b, u, v), o3 = orient2(a, b, p, u, v), o4 = orient2(a, b, q, u, v);
  if (o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0) {  // on one line: do their extents overlap?
    for (const int k : {u, v})
      if (std::max(p[k], q[k]) < std::min(a[k], b[k]) || std::max(a[k], b[k]) < std::min(p[k], q[k])) return false;
    return true;
  }
  return o1 * o2 <= 0 && o3 * o4 <= 0;
}

/// A segment lying in the plane of triangle abc (both ends' orientations zero): does it touch the
/// triangle? (An end inside, or a crossing with an edge; touching counts, as above.)
inline bool coplanar_segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a).cwiseAbs();
  const int drop = n[0] >= n[1] && n[0] >= n[2] ? 0 : n[1] >= n[2] ? 1 : 2;
  const int u = (drop + 1) % 3, v = (drop + 2) % 3;
  for (const Vec3* e : {&p, &q}) {
    const int s0 = orient2(a, b, *e, u, v), s1 = orient2(b, c, *e, u, v), s2 = orient2(c, a, *e, u, v);
    if (!((s0 > 0 || s1 > 0 || s2 > 0) && (s0 < 0 || s1 < 0 || s2 < 0))) return true;
  }
  return segments2_touch(p, q, a, b, u, v) || segments2_touch(p, q, b, c, u, v) || segments2_touch(p, q, c, a, u, v);
}

/// Does segment pq touch triangle abc (up to the filter above)?
inline bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  if (sp != 0 && sp == sq) return false;  // both strictly on one side
  // In the triangle's plane (a flat face's triangles side by side): only an overlap within the plane counts.
  if (sp == 0 && sq == 0) return coplanar_segment_hits_triangle(p, q, a, b, c);
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

/// A closed slab [lo, hi] as 12 triangles (outward normals).
struct Slab {
  Eigen::Matrix3Xd V{3, 8};
  Eigen::Matrix3Xi T{3, 12};
  Vec3 lo, hi;
  Slab(const Vec3& lo_, const Vec3& hi_) : lo(lo_), hi(hi_) {
    for (int i = 0; i < 8; ++i) V.col(i) = Vec3(i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]);
    int t = 0;
    for (int axis = 0; axis < 3; ++axis)  // the two faces across each axis, two triangles each
      for (int side = 0; side < 2; ++side) {
        const int b = 1 << ((axis + 1) % 3), c = 1 << ((axis + 2) % 3), s = side << axis;
        T.col(t++) << s, s + b, s + b + c;
        T.col(t++) << s, s + b + c, s + c;
      }
  }
};

}  // namespace snh
