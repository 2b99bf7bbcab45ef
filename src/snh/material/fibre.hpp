#pragma once
// Fibres: the stiffness of a material along one unit direction a of its rest frame (a muscle's fibres),
// added to an isotropic energy, and active strain, the fibres' rest length shortened by an activation.
// docs/math.md ("Fibres and activation") derives every formula here.
//
// A fibre energy is a function of the fibre's squared stretch I4 = ‖F a‖² = aᵀ C a (C = FᵀF) and, for the
// inversion-safe model, of the sign of aᵀ S a (F = R S the polar decomposition, S symmetric, with a negative
// eigenvalue where F is inverted): ψ(F) = f(I4, σ). Then
//     P = 2 f′ F a aᵀ,     ∂P/∂F = 2 f′ (a aᵀ ⊗ I) + 4 f″ g gᵀ,   g = vec(F a aᵀ) = a ⊗ F a
// (column-major vec), whose eigensystem is closed-form: λ = 2 f′ + 4 I4 f″ on a ⊗ q (q = F a / ‖F a‖),
// λ = 2 f′ on a ⊗ q⊥ for the two unit q⊥ orthogonal to q, and 0 on the six b ⊗ e_i, c ⊗ e_i (b, c
// completing a to an orthonormal basis).
#include <string_view>

#include "snh/material/eigensystem.hpp"
#include "snh/material/psd_projection.hpp"
#include "snh/math/types.hpp"

namespace snh {

enum class FibreModel {
  /// ψ = (k/8)(I4 − 1)²: Green's strain along the fibre, squared (St. Venant–Kirchhoff along a). Smooth
  /// everywhere; it takes a fibre reversed by an inverted element as stretched, and stiffens only with I4.
  quadratic,
  /// ψ = (k/2)(s − 1)² with s = sign(aᵀ S a)·√I4 the signed stretch (Kim, Shinar & Smith 2019: "anisotropic
  /// ARAP"): a fibre reversed by inversion counts as compressed past zero length, and pushes back out. Its
  /// eigenvalues are k and k(1 − sign/√I4) twice. ψ jumps where aᵀ S a changes sign with F a ≠ 0 (as
  /// published): a set of measure zero that a step crosses only through an inverted element.
  signed_arap,
};

[[nodiscard]] std::string_view to_string(FibreModel m);

/// sign(aᵀ S a) for F = R S (S from the rotation-variant SVD: S = V diag(σ) Vᵀ, σ signed); +1 where it is 0.
[[nodiscard]] double fibre_sign(const Mat3& F, const Vec3& a);

/// A fibre energy ψ(F; a) of stiffness k (Pa, ≥ 0), a a unit vector of the rest frame.
struct FibreEnergy {
  FibreModel model = FibreModel::signed_arap;
  double stiffness = 0.0;

  /// f(I4), f′ and f″ at the sign σ (±1; the quadratic model ignores it). Where the fibre has collapsed
  /// (I4 = 0) the signed model's f′ is unbounded: there P = 0 and the two transverse eigenvalues are taken
  /// as 0 (the value a projection would give them).
  struct Scalar {
    double f = 0.0, df = 0.0, d2f = 0.0;
  };
  [[nodiscard]] Scalar scalar(double I4, double sign) const;

  [[nodiscard]] double psi(const Mat3& F, const Vec3& a) const;
  [[nodiscard]] Mat3 pk1(const Mat3& F, const Vec3& a) const;
  [[nodiscard]] Mat9 hessian(const Mat3& F, const Vec3& a) const;
  /// The closed-form eigensystem: values[0] on a ⊗ q, values[1..2] on a ⊗ q⊥, values[3..8] = 0.
  [[nodiscard]] Eigensystem9 eigensystem(const Mat3& F, const Vec3& a) const;
  /// ∂P/∂F with its eigenvalues projected (none: hessian()).
  [[nodiscard]] Mat9 projected_hessian(const Mat3& F, const Vec3& a, PsdProjection p) const;
};

/// Active strain along a: the fibre's rest length shortened to 1 − α (α = γ · activation ∈ [0, 1)), the
/// cross-section widened to keep the volume:
///     F_a = (1 − α) a aᵀ + (1 − α)^(−1/2) (I − a aᵀ),   det F_a = 1, symmetric.
/// A material ψ acts on the elastic part F_e = F F_a⁻¹, so ψ_a(F) = ψ(F A) with A = F_a⁻¹, and
///     P_a = P(F A) A,   ∂P_a/∂F = (A ⊗ I) ∂P/∂F(F A) (A ⊗ I)
/// (a congruence: a PSD-projected ∂P/∂F stays PSD). A body that nothing holds rests where F = R F_a.
struct ActiveStrain {
  Mat3 inverse = Mat3::Identity();  ///< A = F_a⁻¹ = (1 − α)⁻¹ a aᵀ + (1 − α)^(1/2) (I − a aᵀ)
  double alpha = 0.0;               ///< α (for output)

  /// Throws std::invalid_argument (one line) unless a is finite and nonzero (it is normalised) and α is
  /// finite in [0, 1).
  [[nodiscard]] static ActiveStrain along(const Vec3& a, double alpha);
  /// F_a itself (for tests and output).
  [[nodiscard]] Mat3 deformation() const { return inverse.inverse(); }

  [[nodiscard]] Mat3 elastic(const Mat3& F) const { return F * inverse; }
  /// P = P_e A from the elastic part's P_e.
  [[nodiscard]] Mat3 pk1(const Mat3& P_elastic) const { return P_elastic * inverse; }
  /// (A ⊗ I) H_e (A ⊗ I) from the elastic part's ∂P/∂F.
  [[nodiscard]] Mat9 hessian(const Mat9& H_elastic) const;
};

}  // namespace snh
