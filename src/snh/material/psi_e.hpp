#pragma once
// Ψ_E (docs/math.md §1): Ψ = μ/2 (I_C − 3) − μ (J − 1) + λ/2 (J − 1)². Rest stable and defined everywhere;
// equal to the production Stable Neo-Hookean (with λ the same) including the constant.
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct PsiE : InvariantEnergy<PsiE> {
  static constexpr std::string_view name = "psi_e";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) - mu (J - 1) + lambda/2 (J - 1)^2";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit PsiE(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Matches linear elasticity at F = I with μ = μ_L, λ = λ_L + μ_L (as production SNH).
  [[nodiscard]] static Lame from_linear(const Lame& l) { return {l.mu, l.lambda + l.mu}; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    return 0.5 * mu * (I2 - 3.0) - mu * (I3 - 1.0) + 0.5 * lambda * (I3 - 1.0) * (I3 - 1.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double I3) const {
    InvariantDerivatives d;
    d.d2 = 0.5 * mu;
    d.d3 = -mu + lambda * (I3 - 1.0);
    d.d33 = lambda;
    return d;
  }
};

}  // namespace snh
