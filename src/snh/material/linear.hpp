#pragma once
// Linear elasticity: Ψ = μ ε:ε + λ/2 tr²(ε), ε = (F + Fᵀ)/2 − I. Not rotation invariant; its Hessian
// μ(I₉ + T) + λ vec(I)vec(I)ᵀ is constant and PSD, with a fixed eigensystem.
#include <string_view>

#include "snh/material/eigensystem.hpp"
#include "snh/material/lame.hpp"
#include "snh/math/types.hpp"

namespace snh {

struct Linear {
  static constexpr std::string_view name = "linear";
  static constexpr std::string_view formula = "mu eps:eps + lambda/2 tr^2(eps), eps = (F + F^T)/2 - I";
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit Linear(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// It is linear elasticity: no change.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return l; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] bool defined(const Mat3&) const { return true; }

  [[nodiscard]] double psi(const Mat3& F) const {
    const Mat3 eps = strain(F);
    const double tr = eps.trace();
    return mu * eps.squaredNorm() + 0.5 * lambda * tr * tr;
  }
  /// P = 2με + λ tr(ε) I.
  [[nodiscard]] Mat3 pk1(const Mat3& F) const {
    const Mat3 eps = strain(F);
    return 2.0 * mu * eps + lambda * eps.trace() * Mat3::Identity();
  }
  [[nodiscard]] Mat9 hessian(const Mat3&) const {
    const Vec9 v = vec(Mat3::Identity());
    Mat9 H = mu * (Mat9::Identity() + transpose_permutation());
    H.noalias() += lambda * v * v.transpose();
    return H;
  }
  /// Fixed eigensystem (independent of F): antisymmetric "twist" 0, symmetric off-diagonal "flip" 2μ,
  /// diagonal "scaling" block A = 2μI + λ11ᵀ.
  [[nodiscard]] Eigensystem9 eigensystem() const {
    const Svd3 frame{Mat3::Identity(), Vec3::Ones(), Mat3::Identity()};
    SigmaEigenvalues s;
    s.twist.setZero();
    s.flip = Vec3::Constant(2.0 * mu);
    s.A = 2.0 * mu * Mat3::Identity() + lambda * Mat3::Ones();
    return assemble_eigensystem(frame, s);
  }

 private:
  [[nodiscard]] static Mat3 strain(const Mat3& F) {
    return 0.5 * (F + F.transpose()) - Mat3::Identity();
  }
};

}  // namespace snh
