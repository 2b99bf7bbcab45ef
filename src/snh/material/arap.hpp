#pragma once
// As-rigid-as-possible: Ψ = μ ‖F − R‖² = μ (I_C − 2 I1 + 3), R from the rotation-variant SVD.
// No volume term (λ is ignored).
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

struct Arap : InvariantEnergy<Arap> {
  static constexpr std::string_view name = "arap";
  static constexpr std::string_view formula = "mu ||F - R||^2 (lambda unused)";
  static constexpr bool uses_I1 = true;
  static constexpr bool inversion_safe = true;

  double mu, lambda;

  explicit Arap(const Lame& p) : mu(p.mu), lambda(p.lambda) { validate(p); }
  [[nodiscard]] static Lame from_linear(const Lame&) {
    throw ParameterError("arap cannot be reparametrized: it has no volume term, so lambda cannot be matched");
  }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double I1, double I2, double) const {
    return mu * (I2 - 2.0 * I1 + 3.0);
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double) const {
    InvariantDerivatives d;
    d.d1 = -2.0 * mu;
    d.d2 = mu;
    return d;
  }
};

}  // namespace snh
