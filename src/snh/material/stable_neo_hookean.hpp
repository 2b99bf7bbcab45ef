#pragma once
// Production Stable Neo-Hookean (docs/math.md §1): Ψ = μ/2 (I_C − 3) + λ/2 (J − α)² − μ²/(2λ), α = 1 + μ/λ.
// The constant makes Ψ(I) = 0; it equals psi_e exactly. Closed-form eigensystem: docs/math.md §4.
#include <string_view>

#include "snh/material/invariant_energy.hpp"
#include "snh/material/lame.hpp"

namespace snh {

/// The closed-form σ-frame eigenvalues shared by both Stable Neo-Hookean forms (docs/math.md §4):
/// twist k τ + λ(J−α)σ_k, flip k τ − λ(J−α)σ_k, A_ii = τ + cσ_i² + λσ_j²σ_k²,
/// A_ij = cσ_iσ_j + λσ_k(2J − α). Production form: τ = μ, c = 0;
/// log form: τ = μ(1 − 1/(I_C+1)), c = 2μ/(I_C+1)².
[[nodiscard]] inline SigmaEigenvalues snh_sigma_eigenvalues(const Vec3& s, double tau, double c, double lambda,
                                                            double alpha) {
  SigmaEigenvalues out;
  const double J = s.prod();
  const double t = lambda * (J - alpha);
  out.twist = Vec3::Constant(tau) + t * s;
  out.flip = Vec3::Constant(tau) - t * s;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    out.A(k, k) = tau + c * s[k] * s[k] + lambda * s[i] * s[i] * s[j] * s[j];
    out.A(i, j) = out.A(j, i) = c * s[i] * s[j] + lambda * s[k] * (2.0 * J - alpha);
  }
  return out;
}

struct StableNeoHookean : InvariantEnergy<StableNeoHookean> {
  static constexpr std::string_view name = "stable_neo_hookean";
  static constexpr std::string_view formula = "mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 - mu^2/(2 lambda), alpha = 1 + mu/lambda";
  static constexpr bool uses_I1 = false;
  static constexpr bool inversion_safe = true;

  double mu, lambda, alpha;

  explicit StableNeoHookean(const Lame& p) : mu(p.mu), lambda(p.lambda), alpha(1.0 + p.mu / p.lambda) {
    validate(p);
    if (!(p.lambda > 0.0)) throw ParameterError("stable_neo_hookean needs lambda > 0 (alpha = 1 + mu/lambda)");
  }
  /// Lamé reparametrization (docs/math.md §2): μ = μ_L, λ = λ_L + μ_L.
  [[nodiscard]] static Lame from_linear(const Lame& l) { return {l.mu, l.lambda + l.mu}; }
  [[nodiscard]] Lame params() const { return {mu, lambda}; }

  [[nodiscard]] double invariant_psi(double, double I2, double I3) const {
    const double r = I3 - alpha;
    return 0.5 * mu * (I2 - 3.0) + 0.5 * lambda * r * r - 0.5 * mu * mu / lambda;
  }
  [[nodiscard]] InvariantDerivatives derivatives(double, double, double I3) const {
    InvariantDerivatives d;
    d.d2 = 0.5 * mu;
    d.d3 = lambda * (I3 - alpha);
    d.d33 = lambda;
    return d;
  }
  /// Closed form (docs/math.md §4): twist k μ + λ(J−α)σ_k, flip k μ − λ(J−α)σ_k,
  /// A_ii = μ + λσ_j²σ_k², A_ij = λσ_k(2J − α).
  [[nodiscard]] SigmaEigenvalues sigma_eigenvalues(const Vec3& s) const {
    return snh_sigma_eigenvalues(s, mu, 0.0, lambda, alpha);
  }
};

}  // namespace snh
