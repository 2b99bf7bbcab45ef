#include "snh/contact/pair_barrier.hpp"

#include <cmath>
#include <limits>

#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/contact/project_psd.hpp"

namespace snh::contact {
namespace {

/// The pair's energy when out of range (all zero), in contact (+∞) or at non-finite positions (NaN).
Derivatives<12> outside(double s) {
  Derivatives<12> z;
  if (s <= 0.0) z.value = std::numeric_limits<double>::infinity();
  if (std::isnan(s)) z.value = std::numeric_limits<double>::quiet_NaN();
  return z;
}

}  // namespace

Derivatives<12> point_triangle_barrier(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2, double s_hat,
                                       bool project) {
  const PointTriangleType type = point_triangle_distance_type(p, t0, t1, t2);
  const double s = point_triangle_distance(p, t0, t1, t2, type);
  if (!(s > 0.0 && s < s_hat)) return outside(s);
  Derivatives<12> b = barrier_of(point_triangle_distance_derivatives(p, t0, t1, t2, type), s_hat);
  if (project) b.hessian = project_psd(b.hessian);
  return b;
}

Derivatives<12> edge_edge_barrier(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1, double s_hat,
                                  double mollifier_threshold, bool project) {
  const EdgeEdgeType type = edge_edge_distance_type(ea0, ea1, eb0, eb1);
  const double s = edge_edge_distance(ea0, ea1, eb0, eb1, type);
  if (!(s > 0.0 && s < s_hat)) return outside(s);
  Derivatives<12> f = barrier_of(edge_edge_distance_derivatives(ea0, ea1, eb0, eb1, type), s_hat);
  const Derivatives<12> m = edge_edge_mollifier_derivatives(ea0, ea1, eb0, eb1, mollifier_threshold);
  if (m.value != 1.0) {  // inside the threshold: the product rule (m = 1 has zero derivatives)
    const Mat12 cross = m.gradient * f.gradient.transpose();
    f.hessian = m.value * f.hessian + cross + cross.transpose() + f.value * m.hessian;
    f.gradient = m.value * f.gradient + f.value * m.gradient;
    f.value *= m.value;
  }
  if (project) f.hessian = project_psd(f.hessian);
  return f;
}

}  // namespace snh::contact
