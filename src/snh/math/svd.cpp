#include "snh/math/svd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace snh {
namespace {

constexpr double kEps = 2.220446049250313e-16;
constexpr int kMaxSweeps = 24;

struct Rotation {
  double c, s;
};

/// The Jacobi rotation (c, s) that diagonalises the symmetric 2x2 [[app, apq], [apq, aqq]]
/// (Golub & Van Loan §8.5; t = s/c is the root of smaller magnitude of t² + 2ζt − 1 = 0,
/// ζ = (aqq − app)/(2apq)). Small angles, the common case after the first sweep, take a
/// division-only path: t = x(1 − x²), x = apq/(aqq − app), exact to a relative 2x⁴ ≤ 2e-16.
inline Rotation jacobi_rotation(double app, double aqq, double apq) {
  const double d = aqq - app;
  if (std::abs(apq) < 1e-4 * std::abs(d)) {
    const double x = apq / d;
    const double t = x * (1.0 - x * x);
    const double t2 = t * t;
    const double c = 1.0 - t2 * (0.5 - 0.375 * t2);  // 1/sqrt(1 + t²) to O(t⁶)
    return {c, t * c};
  }
  // t = sgn(ζ)/(|ζ| + √(1 + ζ²)) rewritten as 2apq·sgn(d)/w with w = |d| + √(d² + 4apq²), so that
  // c = w/√(w² + 4apq²) and s = 2apq·sgn(d)/√(w² + 4apq²): two square roots and one division.
  const double e = 2.0 * apq;
  const double w = std::abs(d) + std::sqrt(d * d + e * e);
  const double inv = 1.0 / std::sqrt(w * w + e * e);
  return {w * inv, (d >= 0.0 ? e : -e) * inv};
}

/// Swap columns i and j of B and V, negating one of them so that det V stays +1 (B = F V holds still).
inline void swap_columns(Mat3& B, Mat3& V, Vec3& norm2, int i, int j) {
  B.col(i).swap(B.col(j));
  V.col(i).swap(V.col(j));
  B.col(j) = -B.col(j);
  V.col(j) = -V.col(j);
  std::swap(norm2[i], norm2[j]);
}

/// A unit vector orthogonal to the unit vector u.
inline Vec3 any_orthogonal(const Vec3& u) {
  int m = 0;
  if (std::abs(u[1]) < std::abs(u[m])) m = 1;
  if (std::abs(u[2]) < std::abs(u[m])) m = 2;
  return u.cross(Vec3::Unit(m)).normalized();
}

/// A rotation close to the eigenvectors of the symmetric S (Eigen's closed-form 3x3 solver, accurate
/// to ~1e-8 in its worst cases), re-orthonormalised to the last ulp, columns by decreasing eigenvalue.
/// Only a starting point: the Jacobi iterations that follow make the result exact.
inline Mat3 orthonormal_start(const Mat3& S) {
  Eigen::SelfAdjointEigenSolver<Mat3> direct;
  direct.computeDirect(S);
  const Mat3& E = direct.eigenvectors();
  Vec3 v0 = E.col(2);
  Vec3 v1 = E.col(1);
  const double n0 = v0.norm();
  v0 = n0 > 0.5 && v0.allFinite() ? Vec3(v0 / n0) : Vec3::UnitX();
  v1 -= v0.dot(v1) * v0;
  const double n1 = v1.norm();
  v1 = n1 > 0.5 && v1.allFinite() ? Vec3(v1 / n1) : any_orthogonal(v0);
  Mat3 V;
  V.col(0) = v0;
  V.col(1) = v1;
  V.col(2) = v0.cross(v1);
  return V;
}

}  // namespace

Svd3 rotation_variant_svd(const Mat3& F) {
  Svd3 out;
  const double max_abs = F.cwiseAbs().maxCoeff();
  const bool finite = F.allFinite();
  if (!finite || max_abs == 0.0) {  // a non-finite entry, or F = 0
    out.U.setIdentity();
    out.V.setIdentity();
    out.sigma = Vec3::Constant(finite ? 0.0 : std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  // Scale by a power of two so ‖F‖ ~ 1: exact, and no under/overflow in the squared norms below.
  int exponent = 0;
  std::frexp(max_abs, &exponent);
  Mat3 B;
  // Scaling by a power of two is exact; ldexp only where 2^(∓exponent) itself would not be a normal number.
  const bool plain = exponent > -1000 && exponent < 1000;
  const double down = plain ? std::ldexp(1.0, -exponent) : 0.0, up = plain ? std::ldexp(1.0, exponent) : 0.0;
  for (int k = 0; k < 9; ++k) B.data()[k] = plain ? F.data()[k] * down : std::ldexp(F.data()[k], -exponent);
  // Starting rotation: eigenvectors of BᵀB from Eigen's closed-form 3x3 solver, made exactly
  // orthonormal. The Jacobi sweeps below then only polish: a few small-angle rotations and a check.
  Mat3 V = orthonormal_start(B.transpose() * B);
  B = (B * V).eval();

  // One-sided Jacobi: rotate pairs of columns of B = F V until they are mutually orthogonal.
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int pair = 0; pair < 3; ++pair) {
      const int p = pair == 2 ? 1 : 0;
      const int q = pair == 0 ? 1 : 2;
      const double a = B.col(p).squaredNorm();
      const double b = B.col(q).squaredNorm();
      const double c = B.col(p).dot(B.col(q));
      if (c * c <= kEps * kEps * a * b) continue;
      rotated = true;
      const auto [cs, sn] = jacobi_rotation(a, b, c);
      const Vec3 bp = B.col(p), bq = B.col(q);
      B.col(p) = cs * bp - sn * bq;
      B.col(q) = sn * bp + cs * bq;
      const Vec3 vp = V.col(p), vq = V.col(q);
      V.col(p) = cs * vp - sn * vq;
      V.col(q) = sn * vp + cs * vq;
    }
    if (!rotated) break;
  }

  // Sort the columns by decreasing norm (three compare-and-swaps).
  Vec3 norm2(B.col(0).squaredNorm(), B.col(1).squaredNorm(), B.col(2).squaredNorm());
  if (norm2[0] < norm2[1]) swap_columns(B, V, norm2, 0, 1);
  if (norm2[1] < norm2[2]) swap_columns(B, V, norm2, 1, 2);
  if (norm2[0] < norm2[1]) swap_columns(B, V, norm2, 0, 1);

  // Complete U as a rotation; the sign of det F lands on σ2.
  // B is scaled so its largest entry is in [1/2, 1): b0, the longest column, has n0 > 1/4. The other
  // columns may be as small as the ratio σ1/σ0 makes them, down to subnormal: u1 is normalised after
  // dividing by its largest entry, so that σ1 down to ~1e-300 σ0 keeps its direction and the sign of
  // det F (an absolute "tiny" cut-off of 1e-150 here turned diag(1e150, 1, 1) into σ = (1e150, 1, −1)).
  const double n0 = std::sqrt(norm2[0]);
  Vec3 u0 = n0 > 0.0 ? Vec3(B.col(0) / n0) : Vec3::UnitX();
  Vec3 u1 = B.col(1) - u0.dot(B.col(1)) * u0;
  double s1 = u1.norm();  // ≤ ‖b1‖ ≤ ‖b0‖ = σ0 up to rounding
  const double m1 = u1.cwiseAbs().maxCoeff();
  if (s1 > 1e-150) {  // the common case, arithmetic unchanged (whole runs stay bit-identical)
    u1 /= s1;
    s1 = std::min(s1, n0);
  } else if (m1 > 0.0 && std::isfinite(1.0 / m1)) {  // tiny: its square would underflow
    u1 /= m1;
    const double n1 = u1.norm();
    u1 /= n1;
    s1 = std::min(m1 * n1, n0);
  } else {
    u1 = any_orthogonal(u0);
    s1 = std::abs(u1.dot(B.col(1)));
  }
  const Vec3 u2 = u0.cross(u1);
  double s2 = u2.dot(B.col(2));
  if (std::abs(s2) > s1) s2 = s2 < 0.0 ? -s1 : s1;  // equal up to rounding: keep |σ2| ≤ σ1
  out.U.col(0) = u0;
  out.U.col(1) = u1;
  out.U.col(2) = u2;
  out.sigma = plain ? Vec3(n0 * up, s1 * up, s2 * up)
                   : Vec3(std::ldexp(n0, exponent), std::ldexp(s1, exponent), std::ldexp(s2, exponent));
  out.V = V;
  return out;
}

Svd3 move_reflection(const Svd3& svd, int k) {
  int s = -1;
  for (int i = 0; i < 3; ++i)
    if (svd.sigma[i] < 0.0) s = i;
  if (s < 0 || s == k) return svd;
  Svd3 out = svd;
  out.sigma[s] = -out.sigma[s];
  out.sigma[k] = -out.sigma[k];
  out.U.col(s) = -out.U.col(s);
  out.U.col(k) = -out.U.col(k);
  return out;
}

SymEigen3 symmetric_eigen3(const Mat3& A) {
  // (Starting from orthonormal_start(A) instead of I was tried: no faster for 3x3, so the plain start stays.)
  Mat3 a = 0.5 * (A + A.transpose());
  Mat3 Q = Mat3::Identity();
  const double tol = 0.25 * kEps * a.norm();
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    bool rotated = false;
    for (int pair = 0; pair < 3; ++pair) {
      const int p = pair == 2 ? 1 : 0;
      const int q = pair == 0 ? 1 : 2;
      const int r = 3 - p - q;
      const double apq = a(p, q);
      if (std::abs(apq) <= tol) continue;
      rotated = true;
      const auto [c, s] = jacobi_rotation(a(p, p), a(q, q), apq);
      const double t = s / c;
      // a ← Gᵀ a G in place, G the rotation in the (p, q) plane.
      a(p, p) -= t * apq;
      a(q, q) += t * apq;
      a(p, q) = a(q, p) = 0.0;
      const double arp = a(r, p), arq = a(r, q);
      a(r, p) = a(p, r) = c * arp - s * arq;
      a(r, q) = a(q, r) = s * arp + c * arq;
      const Vec3 qp = Q.col(p), qq = Q.col(q);
      Q.col(p) = c * qp - s * qq;
      Q.col(q) = s * qp + c * qq;
    }
    if (!rotated) break;
  }
  return {a.diagonal(), Q};
}

}  // namespace snh
