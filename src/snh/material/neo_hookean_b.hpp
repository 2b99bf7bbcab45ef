#pragma once
// Neo-Hookean Ψ_B of the thesis ("Bower 2009", docs/math.md §1): Ψ = μ/2 (J^(−2/3) I_C − 3) + λ/2 (J − 1)².
// Undefined for J ≤ 0. Here λ plays the role of the bulk modulus: at small strain it matches linear
// elasticity with λ_L = λ − 2μ/3.
#include <cmath>
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct NeoHookeanB : InvariantEnergy<NeoHookeanB> {
  static constexpr std::string_view name = "neo_hookean_b";
  static constexpr std::string_view formula = "mu/2 (J^(-2/3) I_C - 3) + lambda/2 (J - 1)^2";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = false;

  double mu, lambda;

  explicit NeoHookeanB(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  /// Matches linear elasticity at F = I with μ = μ_L, λ = λ_L + 2μ_L/3 (the bulk modulus).
  [[nodiscard]] static Lame from_linear(const Lame& l) { return {l.mu, l.lambda + 2.0 * l.mu / 3.0}; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    return 0.5 * mu * (std::pow(I3, -2.0 / 3.0) * I2 - 3.0) + 0.5 * lambda * (I3 - 1.0) * (I3 - 1.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double I2, double I3) const {
    InvariantDerivatives d;
    const double j23 = std::pow(I3, -2.0 / 3.0);  // J^(−2/3)
    const double j53 = j23 / I3;                  // J^(−5/3)
    d.d2 = 0.5 * mu * j23;
    d.d3 = -mu / 3.0 * I2 * j53 + lambda * (I3 - 1.0);
    d.d23 = -mu / 3.0 * j53;
    d.d33 = 5.0 * mu / 9.0 * I2 * j53 / I3 + lambda;
    return d;
  }
};

}  // namespace snh
