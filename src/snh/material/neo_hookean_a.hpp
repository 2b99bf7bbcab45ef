#pragma once
// Neo-Hookean Ψ_A of the thesis ("Ogden 1997", docs/math.md §1): Ψ = μ/2 (I_C − 3) − μ log J + λ/2 (J − 1)².
// Undefined for J ≤ 0.
#include <cmath>
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct NeoHookeanA : InvariantEnergy<NeoHookeanA> {
  static constexpr std::string_view name = "neo_hookean_a";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) - mu log J + lambda/2 (J - 1)^2";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = false;

  double mu, lambda;

  explicit NeoHookeanA(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Already matches linear elasticity at F = I: no change.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return l; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    return 0.5 * mu * (I2 - 3.0) - mu * std::log(I3) + 0.5 * lambda * (I3 - 1.0) * (I3 - 1.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double I3) const {
    InvariantDerivatives d;
    d.d2 = 0.5 * mu;
    d.d3 = -mu / I3 + lambda * (I3 - 1.0);
    d.d33 = mu / (I3 * I3) + lambda;
    return d;
  }
};

}  // namespace snh
