#include "snh/contact/ccd.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {
namespace {

using Four = std::array<Vec3, 4>;

/// Additive CCD of two primitives given by four points; distance(x) is their (unsquared) distance and
/// the points [0, split) belong to the first primitive, [split, 4) to the second.
template <class Distance>
double additive_ccd(const Four& x, Four dx, int split, const CcdOptions& options, const char* what,
                    Distance&& distance) {
  for (int i = 0; i < 4; ++i)
    if (!x[i].allFinite() || !dx[i].allFinite())
      throw std::invalid_argument(std::string(what) + ": non-finite position or displacement");
  if (!(options.keep > 0.0 && options.keep < 1.0))
    throw std::invalid_argument(std::string(what) + ": keep must be in (0, 1)");
  const Vec3 mean = 0.25 * (dx[0] + dx[1] + dx[2] + dx[3]);
  double first = 0.0, second = 0.0;
  for (int i = 0; i < 4; ++i) {
    dx[i] -= mean;
    double& bound = i < split ? first : second;
    bound = std::max(bound, dx[i].norm());
  }
  const double speed = first + second;
  if (!std::isfinite(speed))
    throw std::invalid_argument(std::string(what) + ": displacement too large to bound");
  const auto at = [&](double t) {
    Four xt;
    for (int i = 0; i < 4; ++i) xt[i] = x[i] + t * dx[i];
    return distance(xt);
  };
  const double d0 = distance(x);
  if (!(d0 > 0.0)) return 0.0;
  if (speed == 0.0) return 1.0;
  const double floor = options.keep * d0;
  double t = 0.0, d = d0;
  for (long k = 0; k < options.max_iterations; ++k) {
    const double step = (k == 0 ? (1.0 - options.keep) * d0 : 0.9 * d) / speed;
    const double next = t + step;
    if (next >= 1.0) return 1.0;
    const double dn = at(next);
    if (k > 0 && dn < floor) return t;
    t = next;
    d = dn;
  }
  return t;
}

}  // namespace

double point_triangle_ccd(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2, const Vec3& dp,
                          const Vec3& dt0, const Vec3& dt1, const Vec3& dt2, const CcdOptions& options) {
  return additive_ccd({p, t0, t1, t2}, {dp, dt0, dt1, dt2}, 1, options, "point_triangle_ccd",
                      [](const Four& x) { return std::sqrt(point_triangle_distance(x[0], x[1], x[2], x[3])); });
}

double edge_edge_ccd(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1, const Vec3& dea0,
                     const Vec3& dea1, const Vec3& deb0, const Vec3& deb1, const CcdOptions& options) {
  return additive_ccd({ea0, ea1, eb0, eb1}, {dea0, dea1, deb0, deb1}, 2, options, "edge_edge_ccd",
                      [](const Four& x) { return std::sqrt(edge_edge_distance(x[0], x[1], x[2], x[3])); });
}

}  // namespace snh::contact
