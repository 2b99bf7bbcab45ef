#pragma once
// The paper's Stable Neo-Hookean, Eq. 14 (docs/math.md §1):
// Ψ = μ/2 (I_C − 3) + λ/2 (J − α)² − μ/2 log(I_C + 1) − c, α = 1 + 3μ/(4λ), c makes Ψ(I) = 0.
// Closed-form eigensystem: docs/math.md §4.
#include <cmath>
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"
#include "snh/material/stable_neo_hookean.hpp"

namespace snh {

struct StableNeoHookeanLog : InvariantEnergy<StableNeoHookeanLog> {
  static constexpr std::string_view name = "stable_neo_hookean_log";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 - mu/2 log(I_C + 1) - c, alpha = 1 + 3mu/(4lambda), c: psi(I) = 0";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = true;

  double mu, lambda, alpha, rest_offset;

  explicit StableNeoHookeanLog(const Lame& p)
      : mu(p.mu), lambda(p.lambda), alpha(1.0 + 0.75 * p.mu / p.lambda),
        rest_offset(0.5 * p.lambda * (1.0 - alpha) * (1.0 - alpha) - 0.5 * p.mu * std::log(4.0)) {
    validate(p);
    if (!(p.lambda > 0.0)) throw ParameterError("stable_neo_hookean_log needs lambda > 0 (alpha = 1 + 3mu/(4lambda))");
  }
  /// Lamé reparametrization (docs/math.md §2): μ = 4/3 μ_L, λ = λ_L + 5/6 μ_L.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return {4.0 / 3.0 * l.mu, l.lambda + 5.0 / 6.0 * l.mu}; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    const double r = I3 - alpha;
    return 0.5 * mu * (I2 - 3.0) + 0.5 * lambda * r * r - 0.5 * mu * std::log(I2 + 1.0) - rest_offset;
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double I2, double I3) const {
    InvariantDerivatives d;
    const double q = 1.0 / (I2 + 1.0);
    d.d2 = 0.5 * mu * (1.0 - q);
    d.d22 = 0.5 * mu * q * q;
    d.d3 = lambda * (I3 - alpha);
    d.d33 = lambda;
    return d;
  }
  /// Closed form (docs/math.md §4), τ = μ(1 − 1/(I_C+1)), c = 2μ/(I_C+1)²: twist k τ + λ(J−α)σ_k,
  /// flip k τ − λ(J−α)σ_k, A_ii = τ + cσ_i² + λσ_j²σ_k², A_ij = cσ_iσ_j + λσ_k(2J − α).
  [[nodiscard]] SigmaEigenvalues sigma_eigenvalues(const Vec3& s) const {
    const double q = 1.0 / (s.squaredNorm() + 1.0);
    return snh_sigma_eigenvalues(s, mu * (1.0 - q), 2.0 * mu * q * q, lambda, alpha);
  }
};

}  // namespace snh
