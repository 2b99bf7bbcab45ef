#include "snh/contact/distance_type.hpp"

#include <algorithm>
#include <array>

namespace snh::contact {

std::string_view to_string(PointEdgeType t) {
  switch (t) {
    case PointEdgeType::p_e0: return "p_e0";
    case PointEdgeType::p_e1: return "p_e1";
    case PointEdgeType::p_e: return "p_e";
  }
  return "?";
}

std::string_view to_string(PointTriangleType t) {
  constexpr std::array<std::string_view, 7> names = {"p_t0", "p_t1", "p_t2", "p_e0", "p_e1", "p_e2", "p_t"};
  return names[static_cast<int>(t)];
}

std::string_view to_string(EdgeEdgeType t) {
  constexpr std::array<std::string_view, 9> names = {"ea0_eb0", "ea0_eb1", "ea1_eb0", "ea1_eb1", "ea_eb0",
                                                     "ea_eb1",  "ea0_eb",  "ea1_eb",  "ea_eb"};
  return names[static_cast<int>(t)];
}

namespace {

/// The squared distance from p to segment (e0, e1) and its type.
std::pair<double, PointEdgeType> point_segment(const Vec3& p, const Vec3& e0, const Vec3& e1) {
  const PointEdgeType type = point_edge_distance_type(p, e0, e1);
  switch (type) {
    case PointEdgeType::p_e0: return {(p - e0).squaredNorm(), type};
    case PointEdgeType::p_e1: return {(p - e1).squaredNorm(), type};
    case PointEdgeType::p_e: break;
  }
  const Vec3 v = e1 - e0;
  return {(p - e0).cross(v).squaredNorm() / v.squaredNorm(), type};
}

/// The nearest of several (distance, type) candidates; the first one on ties.
template <class T, std::size_t N>
T nearest(const std::array<std::pair<double, T>, N>& candidates) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < N; ++i)
    if (candidates[i].first < candidates[best].first) best = i;
  return candidates[best].second;
}

/// A point-against-segment type mapped to the pair type with the three given names.
template <class T>
std::pair<double, T> mapped(const std::pair<double, PointEdgeType>& d, T at0, T at1, T interior) {
  switch (d.second) {
    case PointEdgeType::p_e0: return {d.first, at0};
    case PointEdgeType::p_e1: return {d.first, at1};
    case PointEdgeType::p_e: break;
  }
  return {d.first, interior};
}

}  // namespace

PointEdgeType point_edge_distance_type(const Vec3& p, const Vec3& e0, const Vec3& e1) {
  const Vec3 v = e1 - e0;
  const double along = (p - e0).dot(v), length2 = v.squaredNorm();
  if (!(length2 > 0.0) || along <= 0.0) return PointEdgeType::p_e0;
  if (along >= length2) return PointEdgeType::p_e1;
  return PointEdgeType::p_e;
}

PointTriangleType point_triangle_distance_type(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  using T = PointTriangleType;
  const Vec3 ab = t1 - t0, ac = t2 - t0;
  if (ab.cross(ac).squaredNorm() <= 1e-20 * ab.squaredNorm() * ac.squaredNorm()) {
    return nearest<T, 3>({mapped(point_segment(p, t0, t1), T::p_t0, T::p_t1, T::p_e0),
                          mapped(point_segment(p, t1, t2), T::p_t1, T::p_t2, T::p_e1),
                          mapped(point_segment(p, t2, t0), T::p_t2, T::p_t0, T::p_e2)});
  }
  // Projections of p − t_i on the two edge directions from t0.
  const Vec3 ap = p - t0, bp = p - t1, cp = p - t2;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return T::p_t0;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return T::p_t1;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return T::p_t2;
  // Each v_i is (twice) the signed area of the sub-triangle opposite t_i, times |n|², of p's projection.
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return T::p_e0;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return T::p_e2;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) return T::p_e1;
  return T::p_t;
}

EdgeEdgeType edge_edge_distance_type(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1) {
  using T = EdgeEdgeType;
  const Vec3 a = ea1 - ea0, b = eb1 - eb0, r = ea0 - eb0;
  const double A = a.squaredNorm(), B = a.dot(b), C = b.squaredNorm(), D = a.dot(r), E = b.dot(r);
  const double det = a.cross(b).squaredNorm();  // = AC − B², without its cancellation
  if (!(det >= kParallelThreshold * A * C) || !(A > 0.0) || !(C > 0.0)) {
    return nearest<T, 4>({mapped(point_segment(ea0, eb0, eb1), T::ea0_eb0, T::ea0_eb1, T::ea0_eb),
                          mapped(point_segment(ea1, eb0, eb1), T::ea1_eb0, T::ea1_eb1, T::ea1_eb),
                          mapped(point_segment(eb0, ea0, ea1), T::ea0_eb0, T::ea1_eb0, T::ea_eb0),
                          mapped(point_segment(eb1, ea0, ea1), T::ea0_eb1, T::ea1_eb1, T::ea_eb1)});
  }
  // Minimise over s with t eliminated (t = (B s + E)/C), then clamp t and re-minimise s if needed.
  // Positions along each segment: 0 → first endpoint, 1 → second, 2 → interior.
  double s = std::clamp((B * E - C * D) / det, 0.0, 1.0);
  const double t_free = B * s + E;  // t·C
  int at_a = s <= 0.0 ? 0 : (s >= 1.0 ? 1 : 2), at_b = 2;
  if (t_free <= 0.0) {
    at_b = 0;
    s = -D / A;
    at_a = s <= 0.0 ? 0 : (s >= 1.0 ? 1 : 2);
  } else if (t_free >= C) {
    at_b = 1;
    s = (B - D) / A;
    at_a = s <= 0.0 ? 0 : (s >= 1.0 ? 1 : 2);
  }
  constexpr T table[3][3] = {{T::ea0_eb0, T::ea0_eb1, T::ea0_eb},
                             {T::ea1_eb0, T::ea1_eb1, T::ea1_eb},
                             {T::ea_eb0, T::ea_eb1, T::ea_eb}};
  return table[at_a][at_b];
}

}  // namespace snh::contact
