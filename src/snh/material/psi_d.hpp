#pragma once
// Ψ_D (docs/math.md §1): Ψ = μ/2 (I_C − 3) + λ/2 (J − 1)². Defined everywhere but not rest stable:
// P(I) = μI, so an unloaded body shrinks.
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct PsiD : InvariantEnergy<PsiD> {
  static constexpr std::string_view name = "psi_d";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) + lambda/2 (J - 1)^2";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit PsiD(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// No Lamé choice matches linear elasticity: its rest Hessian μI₉ + λ vec(I)vec(I)ᵀ lacks μT.
  [[nodiscard]] static Lame from_linear(const Lame&) {
    throw ParameterError("psi_d cannot be reparametrized: its rest Hessian has no mu*T term, so no "
                         "choice of mu, lambda matches linear elasticity");
  }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    return 0.5 * mu * (I2 - 3.0) + 0.5 * lambda * (I3 - 1.0) * (I3 - 1.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double I3) const {
    InvariantDerivatives d;
    d.d2 = 0.5 * mu;
    d.d3 = lambda * (I3 - 1.0);
    d.d33 = lambda;
    return d;
  }
};

}  // namespace snh
