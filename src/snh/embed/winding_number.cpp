#include "snh/embed/winding_number.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>

namespace snh {

void check_triangles(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F) {
  for (Eigen::Index v = 0; v < V.cols(); ++v)
    if (!V.col(v).allFinite())
      throw std::invalid_argument(
          fmt::format("surface vertex {} ({}, {}, {}) is not finite", v, V(0, v), V(1, v), V(2, v)));
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int a = 0; a < 3; ++a)
      if (F(a, f) < 0 || F(a, f) >= V.cols())
        throw std::invalid_argument(
            fmt::format("surface triangle {} refers to vertex {} (there are {} vertices)", f, F(a, f), V.cols()));
}

double winding_number(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, const Eigen::Vector3d& p) {
  if (!p.allFinite())
    throw std::invalid_argument(fmt::format("winding number asked at a non-finite point ({}, {}, {})", p.x(), p.y(), p.z()));
  check_triangles(V, F);
  double sum = 0.0;
  for (Eigen::Index f = 0; f < F.cols(); ++f) {
    const Eigen::Vector3d a = V.col(F(0, f)) - p, b = V.col(F(1, f)) - p, c = V.col(F(2, f)) - p;
    const double det = a.dot(b.cross(c));
    // In the triangle's plane the solid angle is 0; atan2(±0, negative) would give ±π by the sign of a zero.
    if (det == 0.0) continue;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2.0 * std::atan2(det, den);  // Van Oosterom–Strackee: tan(Ω/2) = det / den
  }
  return sum / (4.0 * std::numbers::pi);
}

double enclosed_volume(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F) {
  check_triangles(V, F);
  if (F.cols() == 0) return 0.0;
  // Corners relative to a point near the surface: the sum is translation invariant for a closed surface and
  // loses fewer digits than with the coordinates' origin far away.
  Eigen::Vector3d lo = V.col(F(0, 0)), hi = lo;
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int a = 0; a < 3; ++a) {
      lo = lo.cwiseMin(V.col(F(a, f)));
      hi = hi.cwiseMax(V.col(F(a, f)));
    }
  const Eigen::Vector3d o = 0.5 * (lo + hi);
  double sum = 0.0;
  for (Eigen::Index f = 0; f < F.cols(); ++f) {
    const Eigen::Vector3d a = V.col(F(0, f)) - o, b = V.col(F(1, f)) - o, c = V.col(F(2, f)) - o;
    sum += a.dot(b.cross(c));
  }
  return sum / 6.0;
}

}  // namespace snh
