#pragma once
// Corotated elasticity (McAdams et al. 2011, the paper's comparison):
// Ψ = μ ‖F − R‖² + λ/2 tr²(S − I) = μ (I_C − 2 I1 + 3) + λ/2 (I1 − 3)², with F = RS from the
// rotation-variant SVD (I1 = Σσ signed). Defined everywhere; depends on which σ carries a reflection.
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct Corotated : InvariantEnergy<Corotated> {
  static constexpr std::string_view name = "corotated";
  static constexpr std::string_view formula = "mu ||F - R||^2 + lambda/2 tr^2(S - I)";
  static constexpr bool uses_I1 = true;
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit Corotated(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Already matches linear elasticity at F = I: no change.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return l; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double I1, double I2, double) const {
    return mu * (I2 - 2.0 * I1 + 3.0) + 0.5 * lambda * (I1 - 3.0) * (I1 - 3.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double I1, double, double) const {
    InvariantDerivatives d;
    d.d1 = -2.0 * mu + lambda * (I1 - 3.0);
    d.d2 = mu;
    d.d11 = lambda;
    return d;
  }
};

}  // namespace snh
