#pragma once
// Bonet & Wood Neo-Hookean (docs/math.md §1): Ψ = μ/2 (I_C − 3) − μ log J + λ/2 (log J)². Undefined for J ≤ 0.
#include <cmath>
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct NeoHookean : InvariantEnergy<NeoHookean> {
  static constexpr std::string_view name = "neo_hookean";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) - mu log J + lambda/2 (log J)^2";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = false;

  double mu, lambda;

  explicit NeoHookean(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Already matches linear elasticity at F = I: no change.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return l; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    const double lj = std::log(I3);
    return 0.5 * mu * (I2 - 3.0) - mu * lj + 0.5 * lambda * lj * lj;
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double I3) const {
    InvariantDerivatives d;
    const double lj = std::log(I3);
    d.d2 = 0.5 * mu;
    d.d3 = (lambda * lj - mu) / I3;
    d.d33 = (mu + lambda * (1.0 - lj)) / (I3 * I3);
    return d;
  }
};

}  // namespace snh
