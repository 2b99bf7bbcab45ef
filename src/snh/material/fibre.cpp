#include "snh/material/fibre.hpp"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/math/svd.hpp"

namespace snh {
namespace {

/// Two unit vectors completing the unit u to a right-handed orthonormal basis (u, v, w).
void complete_basis(const Vec3& u, Vec3& v, Vec3& w) {
  // The coordinate axis least aligned with u, made orthogonal to it.
  Eigen::Index k = 0;
  u.cwiseAbs().minCoeff(&k);
  v = Vec3::Unit(k) - u[k] * u;
  v.normalize();
  w = u.cross(v);
}

}  // namespace

std::string_view to_string(FibreModel m) {
  switch (m) {
    case FibreModel::quadratic: return "quadratic";
    case FibreModel::signed_arap: return "signed_arap";
  }
  return "?";
}

double fibre_sign(const Mat3& F, const Vec3& a) {
  const Svd3 svd = rotation_variant_svd(F);
  const Vec3 va = svd.V.transpose() * a;  // a in S's eigenbasis: aᵀ S a = Σ σ_i (v_i · a)²
  return svd.sigma.dot(va.cwiseAbs2()) < 0.0 ? -1.0 : 1.0;
}

FibreEnergy::Scalar FibreEnergy::scalar(double I4, double sign) const {
  const double k = stiffness;
  Scalar s;
  switch (model) {
    case FibreModel::quadratic:
      s.f = 0.125 * k * (I4 - 1.0) * (I4 - 1.0);
      s.df = 0.25 * k * (I4 - 1.0);
      s.d2f = 0.25 * k;
      break;
    case FibreModel::signed_arap: {
      const double r = std::sqrt(std::max(I4, 0.0));
      s.f = 0.5 * k * (sign * r - 1.0) * (sign * r - 1.0);
      if (r > 0.0) {
        s.df = 0.5 * k * (1.0 - sign / r);
        s.d2f = 0.25 * k * sign / (r * r * r);
      }
      break;
    }
  }
  return s;
}

double FibreEnergy::psi(const Mat3& F, const Vec3& a) const {
  const double sign = model == FibreModel::signed_arap ? fibre_sign(F, a) : 1.0;
  return scalar((F * a).squaredNorm(), sign).f;
}

Mat3 FibreEnergy::pk1(const Mat3& F, const Vec3& a) const {
  const Vec3 Fa = F * a;
  const double sign = model == FibreModel::signed_arap ? fibre_sign(F, a) : 1.0;
  return 2.0 * scalar(Fa.squaredNorm(), sign).df * Fa * a.transpose();
}

Mat9 FibreEnergy::hessian(const Mat3& F, const Vec3& a) const {
  const Vec3 Fa = F * a;
  const double I4 = Fa.squaredNorm();
  if (model == FibreModel::signed_arap && !(I4 > 0.0)) return rebuild(eigensystem(F, a), PsdProjection::none);
  const Scalar s = scalar(I4, model == FibreModel::signed_arap ? fibre_sign(F, a) : 1.0);
  // 2 f′ (a aᵀ ⊗ I) + 4 f″ g gᵀ with g = vec(F a aᵀ).
  Mat9 H = Mat9::Zero();
  const Mat3 aa = a * a.transpose();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) H.block<3, 3>(3 * i, 3 * j) = 2.0 * s.df * aa(i, j) * Mat3::Identity();
  const Vec9 g = vec(Fa * a.transpose());
  H += 4.0 * s.d2f * g * g.transpose();
  return H;
}

Eigensystem9 FibreEnergy::eigensystem(const Mat3& F, const Vec3& a) const {
  const Vec3 Fa = F * a;
  const double I4 = Fa.squaredNorm();
  Eigensystem9 es;
  if (model == FibreModel::signed_arap) {
    // λ along the fibre's own direction is k exactly; across it k(1 − σ/√I4), taken as 0 where I4 = 0.
    const double sign = fibre_sign(F, a), r = std::sqrt(I4);
    es.values[0] = stiffness;
    es.values[1] = es.values[2] = r > 0.0 ? stiffness * (1.0 - sign / r) : 0.0;
  } else {
    const Scalar s = scalar(I4, 1.0);
    es.values[0] = 2.0 * s.df + 4.0 * I4 * s.d2f;
    es.values[1] = es.values[2] = 2.0 * s.df;
  }
  Vec3 q = I4 > 0.0 ? Vec3(Fa / std::sqrt(I4)) : Vec3::UnitX(), q1, q2, b, c;
  complete_basis(q, q1, q2);
  complete_basis(a, b, c);
  es.vectors.col(0) = vec(q * a.transpose());
  es.vectors.col(1) = vec(q1 * a.transpose());
  es.vectors.col(2) = vec(q2 * a.transpose());
  for (int i = 0; i < 3; ++i) {
    es.vectors.col(3 + i) = vec(Vec3::Unit(i) * b.transpose());
    es.vectors.col(6 + i) = vec(Vec3::Unit(i) * c.transpose());
  }
  return es;
}

Mat9 FibreEnergy::projected_hessian(const Mat3& F, const Vec3& a, PsdProjection p) const {
  if (p == PsdProjection::none) return hessian(F, a);
  return rebuild(eigensystem(F, a), p);
}

ActiveStrain ActiveStrain::along(const Vec3& a, double alpha) {
  if (!a.allFinite() || !(a.norm() > 0.0))
    throw std::invalid_argument(fmt::format("active strain: the fibre direction ({:g}, {:g}, {:g}) is not a finite nonzero vector",
                                            a[0], a[1], a[2]));
  if (!std::isfinite(alpha) || alpha < 0.0 || alpha >= 1.0)
    throw std::invalid_argument(fmt::format("active strain: the contraction gamma * activation = {:g} must be in [0, 1)", alpha));
  const Vec3 u = a.normalized();
  const Mat3 aa = u * u.transpose();
  ActiveStrain s;
  s.inverse = aa / (1.0 - alpha) + std::sqrt(1.0 - alpha) * (Mat3::Identity() - aa);
  s.alpha = alpha;
  return s;
}

Mat9 ActiveStrain::hessian(const Mat9& H_elastic) const {
  // (A ⊗ I): block (i, j) is A(i, j) I (column-major vec). A is symmetric, so (Aᵀ ⊗ I) = (A ⊗ I).
  Mat9 K = Mat9::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) K.block<3, 3>(3 * i, 3 * j) = inverse(i, j) * Mat3::Identity();
  return K * H_elastic * K;
}

}  // namespace snh
