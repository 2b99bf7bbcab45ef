#pragma once
// Energies written in the invariants I1 = tr S = Σσ, I2 = ‖F‖² = I_C, I3 = J, and the general
// eigensystem of Smith, de Goes & Kim 2019 built from their derivatives (docs/math.md §4).
#include <array>
#include <cmath>
#include <limits>

#include "snh/material/eigensystem.hpp"
#include "snh/math/svd.hpp"
#include "snh/math/types.hpp"

namespace snh {

/// First and second derivatives of Ψ(I1, I2, I3).
struct InvariantDerivatives {
  double d1 = 0, d2 = 0, d3 = 0;
  double d11 = 0, d22 = 0, d33 = 0, d12 = 0, d13 = 0, d23 = 0;
};

/// Twist denominators σ_i + σ_j smaller than this are replaced by ±this (only energies that use I1
/// have that term; their Hessian is genuinely singular there, docs/math.md §4).
inline constexpr double kTwistDenominatorFloor = 1e-10;

/// The σ-frame eigenvalues of a Ψ(I1, I2, I3) at signed singular values σ (docs/math.md §4):
/// twist 2Ψ₁/(σ_i+σ_j) + 2Ψ₂ + σ_kΨ₃, flip 2Ψ₂ − σ_kΨ₃, and the scaling block A = ∇²_σ ψ̂.
[[nodiscard]] inline SigmaEigenvalues invariant_sigma_eigenvalues(const Vec3& s,
                                                                  const InvariantDerivatives& d) {
  SigmaEigenvalues out;
  const double I3 = s[0] * s[1] * s[2];
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    double twist = 2.0 * d.d2 + s[k] * d.d3;
    if (d.d1 != 0.0) {
      double sum = s[i] + s[j];
      if (std::abs(sum) < kTwistDenominatorFloor)
        sum = sum < 0.0 ? -kTwistDenominatorFloor : kTwistDenominatorFloor;
      twist += 2.0 * d.d1 / sum;
    }
    out.twist[k] = twist;
    out.flip[k] = 2.0 * d.d2 - s[k] * d.d3;
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const double pi = s[j] * s[k];  // I3 / σ_i without dividing
    out.A(i, i) = 2.0 * d.d2 + d.d11 + 4.0 * s[i] * s[i] * d.d22 + pi * pi * d.d33 +
                  4.0 * s[i] * d.d12 + 4.0 * I3 * d.d23 + 2.0 * pi * d.d13;
  }
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    const double a = s[k] * d.d3 + d.d11 + 4.0 * s[i] * s[j] * d.d22 + s[k] * I3 * d.d33 +
                     2.0 * s[k] * (s[i] * s[i] + s[j] * s[j]) * d.d23 +
                     (s[i] + s[j]) * (s[k] * d.d13 + 2.0 * d.d12);
    out.A(i, j) = out.A(j, i) = a;
  }
  return out;
}

/// CRTP base for an energy Ψ(I1, I2, I3). The derived type provides
///   static constexpr bool uses_I1;            whether Ψ depends on I1 (then ψ, P, H need the SVD)
///   static constexpr bool inversion_safe;     whether Ψ is defined for J ≤ 0
///   double invariant_psi(I1, I2, I3) const;   Ψ (only called where defined)
///   InvariantDerivatives derivatives(I1, I2, I3) const;
/// and gets ψ, P = ∂Ψ/∂F, ∂P/∂F in F, and ψ̂, ∇ψ̂ and the σ-frame eigenvalues in σ.
/// Where Ψ is undefined (J ≤ 0 for log J or J^(−2/3) energies) ψ = +∞ and P, ∂P/∂F are zero;
/// callers check defined() (or use evaluate(), which reports it).
template <class Derived>
struct InvariantEnergy {
  [[nodiscard]] bool defined(const Mat3& F) const {
    return Derived::inversion_safe || F.determinant() > 0.0;
  }
  [[nodiscard]] bool defined_sigma(const Vec3& s) const {
    return Derived::inversion_safe || s.prod() > 0.0;
  }

  // ---- σ form (rotation-variant SVD) ----
  [[nodiscard]] double psi_sigma(const Vec3& s) const {
    if (!defined_sigma(s)) return std::numeric_limits<double>::infinity();
    return self().invariant_psi(s.sum(), s.squaredNorm(), s.prod());
  }
  [[nodiscard]] Vec3 grad_sigma(const Vec3& s) const {
    if (!defined_sigma(s)) return Vec3::Zero();
    const InvariantDerivatives d = self().derivatives(s.sum(), s.squaredNorm(), s.prod());
    return Vec3::Constant(d.d1) + 2.0 * d.d2 * s + d.d3 * Vec3(s[1] * s[2], s[2] * s[0], s[0] * s[1]);
  }
  [[nodiscard]] SigmaEigenvalues sigma_eigenvalues(const Vec3& s) const {
    if (!defined_sigma(s)) return {Vec3::Zero(), Vec3::Zero(), Mat3::Zero()};
    return invariant_sigma_eigenvalues(s, self().derivatives(s.sum(), s.squaredNorm(), s.prod()));
  }

  // ---- F form ----
  [[nodiscard]] double psi(const Mat3& F) const {
    if constexpr (Derived::uses_I1) {
      return psi_sigma(rotation_variant_svd(F).sigma);
    } else {
      if (!defined(F)) return std::numeric_limits<double>::infinity();
      return self().invariant_psi(0.0, F.squaredNorm(), F.determinant());
    }
  }
  [[nodiscard]] Mat3 pk1(const Mat3& F) const {
    if constexpr (Derived::uses_I1) {
      const Svd3 svd = rotation_variant_svd(F);
      return svd.U * grad_sigma(svd.sigma).asDiagonal() * svd.V.transpose();
    } else {
      if (!defined(F)) return Mat3::Zero();
      const InvariantDerivatives d = self().derivatives(0.0, F.squaredNorm(), F.determinant());
      return 2.0 * d.d2 * F + d.d3 * det_gradient(F);
    }
  }
  /// ∂P/∂F. Without I1: 2Ψ₂I + Ψ₃H_J + 4Ψ₂₂ffᵀ + Ψ₃₃ggᵀ + 2Ψ₂₃(fgᵀ + gfᵀ), f = vec F, g = vec ∂J/∂F.
  /// With I1 it is rebuilt from the eigensystem (∂R/∂F has no simpler closed form).
  [[nodiscard]] Mat9 hessian(const Mat3& F) const {
    if constexpr (Derived::uses_I1) {
      const Svd3 svd = rotation_variant_svd(F);
      return rebuild(assemble_eigensystem(svd, sigma_eigenvalues(svd.sigma)), PsdProjection::none);
    } else {
      if (!defined(F)) return Mat9::Zero();
      const InvariantDerivatives d = self().derivatives(0.0, F.squaredNorm(), F.determinant());
      const Vec9 f = vec(F);
      const Vec9 g = vec(det_gradient(F));
      Mat9 H = d.d3 * det_hessian(F);
      H.diagonal().array() += 2.0 * d.d2;
      H.noalias() += d.d33 * g * g.transpose();
      if (d.d22 != 0.0) H.noalias() += 4.0 * d.d22 * f * f.transpose();
      if (d.d23 != 0.0) {
        const Mat9 fg = f * g.transpose();
        H += 2.0 * d.d23 * (fg + fg.transpose());
      }
      return H;
    }
  }
  /// w ∂P/∂F, the analytic Hessian of an energy without I1 times w, as the six 3×3 slices an element's
  /// stiffness is made of (elastic_term.cpp): slice i(i+1)/2 + k, i ≥ k, holds (j, l) ↦ w H_{3j+i, 3l+k}. Each
  /// entry comes straight from the formula above (∂²J/∂F_ij∂F_kl = ε_ikm ε_jln F_mn), summed in hessian()'s
  /// order, so the values are w·hessian(F)'s to the bit (tested), without the 9×9 matrix, its products and
  /// its zeros (half of the slices' entries come from ∂²J/∂F², zero elsewhere). Zero where undefined.
  template <class D = Derived>  // a template: Derived is complete only where this is used
    requires(!D::uses_I1)
  [[nodiscard]] std::array<Mat3, 6> weighted_hessian_slices(const Mat3& F, double w) const {
    std::array<Mat3, 6> out;
    if (!defined(F)) {
      for (Mat3& m : out) m.setZero();
      return out;
    }
    const InvariantDerivatives d = self().derivatives(0.0, F.squaredNorm(), F.determinant());
    const Mat3 g = det_gradient(F);
    const double twice_d2 = 2.0 * d.d2, four_d22 = 4.0 * d.d22, twice_d23 = 2.0 * d.d23;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k <= i; ++k) {
        Mat3& slice = out[static_cast<std::size_t>(i * (i + 1) / 2 + k)];
        // ε_ikm: m is the third index when i ≠ k, with the sign of the permutation (i, k, m).
        const int m = 3 - i - k;
        const double eps_ik = i == k ? 0.0 : ((k - i + 3) % 3 == 1 ? 1.0 : -1.0);
        for (int j = 0; j < 3; ++j)
          for (int l = 0; l < 3; ++l) {
            const int n = 3 - j - l;
            const double eps_jl = j == l ? 0.0 : ((l - j + 3) % 3 == 1 ? 1.0 : -1.0);
            // ε_ikm ε_jln F_mn is ±F_mn or zero, as det_hessian()'s entries: exactly.
            const double hJ = eps_ik * eps_jl == 0.0 ? 0.0 : eps_ik * eps_jl * F(m, n);
            double h = d.d3 * hJ;
            if (i == k && j == l) h += twice_d2;
            h += (d.d33 * g(i, j)) * g(k, l);
            if (d.d22 != 0.0) h += (four_d22 * F(i, j)) * F(k, l);
            if (d.d23 != 0.0) h += twice_d23 * (F(i, j) * g(k, l) + F(k, l) * g(i, j));
            slice(j, l) = h * w;
          }
      }
    return out;
  }

 private:
  const Derived& self() const { return static_cast<const Derived&>(*this); }
};

}  // namespace snh
