#pragma once
// Fixed-size matrix types and the vec/cross-product helpers used throughout (docs/math.md conventions:
// column-major vec, F = [f0 f1 f2] by columns).
#include <Eigen/Dense>

namespace snh {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Vec9 = Eigen::Matrix<double, 9, 1>;
using Mat9 = Eigen::Matrix<double, 9, 9>;

/// vec(A): the 9 entries of a 3x3 matrix stacked column by column.
inline Vec9 vec(const Mat3& A) { return Eigen::Map<const Vec9>(A.data()); }

/// Inverse of vec: the 3x3 matrix whose columns are v[0:3], v[3:6], v[6:9].
inline Mat3 unvec(const Vec9& v) { return Eigen::Map<const Mat3>(v.data()); }

/// The cross-product matrix: cross_matrix(a) * b == a.cross(b).
inline Mat3 cross_matrix(const Vec3& a) {
  Mat3 m;
  m << 0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0;
  return m;
}

/// ∂J/∂F for J = det F: the columns [f1×f2 | f2×f0 | f0×f1] (docs/math.md §3).
inline Mat3 det_gradient(const Mat3& F) {
  Mat3 g;
  g.col(0) = F.col(1).cross(F.col(2));
  g.col(1) = F.col(2).cross(F.col(0));
  g.col(2) = F.col(0).cross(F.col(1));
  return g;
}

/// ∂²J/∂F² as a 9x9 matrix: [[0, −F̂2, F̂1], [F̂2, 0, −F̂0], [−F̂1, F̂0, 0]] (docs/math.md §3).
inline Mat9 det_hessian(const Mat3& F) {
  Mat9 H = Mat9::Zero();
  const Mat3 f0 = cross_matrix(F.col(0)), f1 = cross_matrix(F.col(1)), f2 = cross_matrix(F.col(2));
  H.block<3, 3>(0, 3) = -f2;
  H.block<3, 3>(0, 6) = f1;
  H.block<3, 3>(3, 0) = f2;
  H.block<3, 3>(3, 6) = -f0;
  H.block<3, 3>(6, 0) = -f1;
  H.block<3, 3>(6, 3) = f0;
  return H;
}

/// The 9x9 permutation T with T vec(A) = vec(Aᵀ).
inline Mat9 transpose_permutation() {
  Mat9 T = Mat9::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) T(3 * j + i, 3 * i + j) = 1.0;
  return T;
}

}  // namespace snh
