#include "snh/contact/surface_distance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

namespace snh::contact {
namespace {

/// Barycentric weights of the point of segment (a, b) nearest p, as (1 − s, s).
std::pair<double, double> nearest_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return {1.0 - s, s};
}

/// The angle at corner a of triangle (a, b, c); 0 where an edge has no length.
double corner_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - a, v = c - a;
  const double s = u.cross(v).norm(), d = u.dot(v);
  return s == 0.0 && d == 0.0 ? 0.0 : std::atan2(s, d);
}

}  // namespace

Vec3 nearest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // The Voronoi regions of the corners, then of the edges, then the face (Ericson, Real-Time Collision
  // Detection §5.1.5): each test is a sign of a dot product of edge vectors with p's offsets.
  const Vec3 ab = b - a, ac = c - a;
  const Vec3 pa = p - a, pb = p - b, pc = p - c;
  const double ab_pa = ab.dot(pa), ac_pa = ac.dot(pa);
  if (ab_pa <= 0.0 && ac_pa <= 0.0) return {1.0, 0.0, 0.0};
  const double ab_pb = ab.dot(pb), ac_pb = ac.dot(pb);
  if (ab_pb >= 0.0 && ac_pb <= ab_pb) return {0.0, 1.0, 0.0};
  const double ab_pc = ab.dot(pc), ac_pc = ac.dot(pc);
  if (ac_pc >= 0.0 && ab_pc <= ac_pc) return {0.0, 0.0, 1.0};
  // The signed areas (times |n|²) of the sub-triangles opposite each corner.
  const double area_c = ab_pa * ac_pb - ab_pb * ac_pa;  // opposite c: p's weight on c
  const double area_b = ab_pc * ac_pa - ab_pa * ac_pc;  // opposite b
  const double area_a = ab_pb * ac_pc - ab_pc * ac_pb;  // opposite a
  const double total = area_a + area_b + area_c;
  if (total > 0.0 && area_a >= 0.0 && area_b >= 0.0 && area_c >= 0.0)
    return {area_a / total, area_b / total, area_c / total};
  // Outside the face (or a triangle without area): the nearest of the three edges.
  Vec3 best(1.0, 0.0, 0.0);
  double best_d2 = std::numeric_limits<double>::infinity();
  const Vec3* corner[3] = {&a, &b, &c};
  for (int e = 0; e < 3; ++e) {
    const int i = e, j = (e + 1) % 3;
    const auto [wi, wj] = nearest_on_segment(p, *corner[i], *corner[j]);
    const double d2 = (p - (wi * *corner[i] + wj * *corner[j])).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = Vec3::Zero();
      best[i] = wi;
      best[j] = wj;
    }
  }
  return best;
}

SurfaceDistance::SurfaceDistance(const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& triangles)
    : vertices_(vertices), triangles_(triangles), normals_(Eigen::Matrix3Xd::Zero(3, vertices.cols())) {
  const Eigen::Index n = vertices.cols(), t = triangles.cols();
  if (t == 0) throw std::invalid_argument("surface distance: the surface has no triangles");
  if (!vertices.allFinite()) throw std::invalid_argument("surface distance: a vertex is not finite");
  if (triangles.minCoeff() < 0 || triangles.maxCoeff() >= n)
    throw std::invalid_argument(fmt::format("surface distance: a triangle refers to a vertex outside 0 to {}", n - 1));
  // One normal per position: vertices at the same place (a seam's copies) share the sum of their corners.
  std::map<std::array<double, 3>, int> place;
  std::vector<int> position_of(static_cast<std::size_t>(n));
  for (Eigen::Index v = 0; v < n; ++v)
    position_of[v] = place.emplace(std::array<double, 3>{vertices(0, v), vertices(1, v), vertices(2, v)}, static_cast<int>(place.size()))
                         .first->second;
  Eigen::Matrix3Xd sum = Eigen::Matrix3Xd::Zero(3, static_cast<Eigen::Index>(place.size()));
  Eigen::Matrix3Xd lo(3, t), hi(3, t);
  for (Eigen::Index f = 0; f < t; ++f) {
    const Vec3 p[3] = {vertices.col(triangles(0, f)), vertices.col(triangles(1, f)), vertices.col(triangles(2, f))};
    const Vec3 normal = (p[1] - p[0]).cross(p[2] - p[0]);
    const double length = normal.norm();
    if (length > 0.0)
      for (int k = 0; k < 3; ++k)
        sum.col(position_of[triangles(k, f)]) += corner_angle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]) * normal / length;
    lo.col(f) = p[0].cwiseMin(p[1]).cwiseMin(p[2]);
    hi.col(f) = p[0].cwiseMax(p[1]).cwiseMax(p[2]);
  }
  for (Eigen::Index v = 0; v < n; ++v) {
    const Vec3 s = sum.col(position_of[v]);
    if (s.norm() > 0.0) normals_.col(v) = s.normalized();
  }
  tree_ = BoxTree(lo, hi);
}

double SurfaceDistance::signed_distance(const Vec3& p, double bound) const {
  if (!p.allFinite() || !(bound >= 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const Vec3 reach = Vec3::Constant(bound * (1.0 + 1e-12) + 1e-300);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Index best_f = -1;
  Vec3 best_w = Vec3::Zero();
  for (const int f : tree_.near(p - reach, p + reach)) {
    const Vec3 a = vertices_.col(triangles_(0, f)), b = vertices_.col(triangles_(1, f)), c = vertices_.col(triangles_(2, f));
    const Vec3 w = nearest_on_triangle(p, a, b, c);
    const double d2 = (p - (w[0] * a + w[1] * b + w[2] * c)).squaredNorm();
    if (d2 < best) {
      best = d2;
      best_f = f;
      best_w = w;
    }
  }
  if (best_f < 0) return std::numeric_limits<double>::quiet_NaN();  // the bound was not one
  const Eigen::Vector3i tri = triangles_.col(best_f);
  const Vec3 c = best_w[0] * vertices_.col(tri[0]) + best_w[1] * vertices_.col(tri[1]) + best_w[2] * vertices_.col(tri[2]);
  Vec3 normal = best_w[0] * normals_.col(tri[0]) + best_w[1] * normals_.col(tri[1]) + best_w[2] * normals_.col(tri[2]);
  if (normal.squaredNorm() == 0.0)
    normal = (vertices_.col(tri[1]) - vertices_.col(tri[0])).cross(vertices_.col(tri[2]) - vertices_.col(tri[0]));
  const double d = std::sqrt(best);
  return (p - c).dot(normal) < 0.0 ? -d : d;
}

double SurfaceDistance::signed_distance(const Vec3& p, Eigen::Index near) const {
  if (near < 0 || near >= vertices_.cols())
    throw std::invalid_argument(fmt::format("surface distance: vertex {} is outside 0 to {}", near, vertices_.cols() - 1));
  return signed_distance(p, (p - vertices_.col(near)).norm());
}

}  // namespace snh::contact
