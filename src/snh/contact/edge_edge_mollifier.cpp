#include "snh/contact/edge_edge_mollifier.hpp"

namespace snh::contact {

double edge_edge_mollifier_threshold(const Vec3& ea0_rest, const Vec3& ea1_rest, const Vec3& eb0_rest,
                                     const Vec3& eb1_rest) {
  return 1e-3 * (ea1_rest - ea0_rest).squaredNorm() * (eb1_rest - eb0_rest).squaredNorm();
}

double edge_edge_mollifier(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1, double threshold) {
  const double x = (ea1 - ea0).cross(eb1 - eb0).squaredNorm();
  if (x >= threshold) return 1.0;
  const double r = x / threshold;
  return (2.0 - r) * r;
}

Derivatives<12> edge_edge_mollifier_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                                double threshold) {
  // x over the two edge vectors a = ea1 − ea0 (difference {1, 0}) and b = eb1 − eb0 (difference {3, 2}).
  const Derivatives<12> x =
      pull_back<2, 4>(cross_squared_norm(ea1 - ea0, eb1 - eb0), {Difference{1, 0}, Difference{3, 2}});
  Derivatives<12> m;
  if (x.value >= threshold) {
    m.value = 1.0;
    return m;
  }
  const double e = threshold, r = x.value / e;
  const double d1 = 2.0 / e - 2.0 * x.value / (e * e), d2 = -2.0 / (e * e);
  m.value = (2.0 - r) * r;
  m.gradient = d1 * x.gradient;
  m.hessian = d2 * x.gradient * x.gradient.transpose() + d1 * x.hessian;
  return m;
}

}  // namespace snh::contact
