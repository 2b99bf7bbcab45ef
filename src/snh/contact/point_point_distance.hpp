#pragma once
// The squared distance |p − q|² between two points, with its gradient (2(p − q), −2(p − q)) and
// Hessian [[2I, −2I], [−2I, 2I]] over (p, q).
#include "snh/contact/distance_core.hpp"

namespace snh::contact {

[[nodiscard]] inline double point_point_distance(const Vec3& p, const Vec3& q) { return (p - q).squaredNorm(); }

[[nodiscard]] inline Derivatives<6> point_point_distance_derivatives(const Vec3& p, const Vec3& q) {
  return point_point_piece<2>({p, q}, 0, 1);
}

}  // namespace snh::contact
