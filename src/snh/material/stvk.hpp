#pragma once
// St. Venant-Kirchhoff: Ψ = μ E:E + λ/2 tr²(E), E = (FᵀF − I)/2. Defined everywhere but softens and
// collapses under compression. Its σ-frame twist/flip eigenvalues are polynomials (no division).
#include <string_view>

#include "snh/material/eigensystem.hpp"
#include "snh/material/lame.hpp"
#include "snh/math/types.hpp"

namespace snh {

struct StVK {
  static constexpr std::string_view name = "stvk";
  static constexpr std::string_view formula = "mu E:E + lambda/2 tr^2(E), E = (F^T F - I)/2";
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit StVK(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Already matches linear elasticity at F = I: no change.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return l; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] bool defined(const Mat3&) const { return true; }
  [[nodiscard]] bool defined_sigma(const Vec3&) const { return true; }

  [[nodiscard]] double psi(const Mat3& F) const {
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    const double tr = E.trace();
    return mu * E.squaredNorm() + 0.5 * lambda * tr * tr;
  }
  /// P = F S with S = 2μE + λ tr(E) I.
  [[nodiscard]] Mat3 pk1(const Mat3& F) const { return F * stress2(F); }
  /// dP = dF S + F dS, dS = 2μ dE + λ tr(dE) I, dE = sym(Fᵀ dF), applied to the 9 unit directions.
  [[nodiscard]] Mat9 hessian(const Mat3& F) const {
    const Mat3 S = stress2(F);
    Mat9 H;
    for (int col = 0; col < 9; ++col) {
      Mat3 dF = Mat3::Zero();
      dF(col % 3, col / 3) = 1.0;
      const Mat3 FtdF = F.transpose() * dF;
      const Mat3 dE = 0.5 * (FtdF + FtdF.transpose());
      const Mat3 dS = 2.0 * mu * dE + lambda * dE.trace() * Mat3::Identity();
      H.col(col) = vec(dF * S + F * dS);
    }
    return H;
  }

  [[nodiscard]] double psi_sigma(const Vec3& s) const {
    const Vec3 e = 0.5 * (s.array().square() - 1.0).matrix();
    const double tr = e.sum();
    return mu * e.squaredNorm() + 0.5 * lambda * tr * tr;
  }
  [[nodiscard]] Vec3 grad_sigma(const Vec3& s) const {
    const double h = 0.5 * lambda * (s.squaredNorm() - 3.0);
    return (mu * (s.array().square() - 1.0) * s.array() + h * s.array()).matrix();
  }
  /// flip k = μ(σ_i² + σ_iσ_j + σ_j² − 1) + λ/2 (I_C − 3), twist k the same with −σ_iσ_j;
  /// A_ii = μ(3σ_i² − 1) + λ/2 (I_C − 3) + λσ_i², A_ij = λσ_iσ_j.
  [[nodiscard]] SigmaEigenvalues sigma_eigenvalues(const Vec3& s) const {
    SigmaEigenvalues out;
    const double h = 0.5 * lambda * (s.squaredNorm() - 3.0);
    for (int k = 0; k < 3; ++k) {
      const int i = (k + 1) % 3, j = (k + 2) % 3;
      const double sq = s[i] * s[i] + s[j] * s[j] - 1.0;
      out.flip[k] = mu * (sq + s[i] * s[j]) + h;
      out.twist[k] = mu * (sq - s[i] * s[j]) + h;
      out.A(k, k) = mu * (3.0 * s[k] * s[k] - 1.0) + h + lambda * s[k] * s[k];
      out.A(i, j) = out.A(j, i) = lambda * s[i] * s[j];
    }
    return out;
  }

 private:
  [[nodiscard]] Mat3 stress2(const Mat3& F) const {
    const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
    return 2.0 * mu * E + lambda * E.trace() * Mat3::Identity();
  }
};

}  // namespace snh
