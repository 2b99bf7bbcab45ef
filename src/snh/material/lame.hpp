#pragma once
// Material parameters: Lamé (μ, λ), Young's modulus / Poisson's ratio, and validation (docs/math.md §2).
#include <stdexcept>
#include <string>

namespace snh {

/// A parameter that is out of range; the message names it and its value.
class ParameterError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Lamé parameters as an energy uses them.
struct Lame {
  double mu = 1.0;
  double lambda = 10.0;
};

/// The supported magnitudes of the Lamé parameters: μ in [kMinModulus, kMaxModulus], λ = 0 or |λ| in
/// the same interval. Beyond them the energies overflow (μ²/λ, α = 1 + μ/λ) or cancel to noise and
/// would print nan or inf; they are refused before any work instead.
inline constexpr double kMinModulus = 1e-12;
inline constexpr double kMaxModulus = 1e12;

/// Throws ParameterError unless μ > 0, λ finite, both within the supported magnitudes above, and the
/// bulk modulus λ + 2μ/3 is positive (equivalently −1 < ν < 0.5).
void validate(const Lame& p);

/// Lamé parameters from Young's modulus E > 0 and Poisson's ratio −1 < ν < 0.5 (thesis Eq. 2.5):
/// μ = E / (2(1+ν)), λ = Eν / ((1+ν)(1−2ν)). Throws ParameterError otherwise.
[[nodiscard]] Lame lame_from_youngs(double youngs, double poisson);

/// Poisson's ratio of linear elasticity with these Lamé parameters: ν = λ / (2(λ + μ)).
[[nodiscard]] double poisson_ratio(const Lame& p);

/// Young's modulus of linear elasticity with these Lamé parameters: E = μ(3λ + 2μ)/(λ + μ).
[[nodiscard]] double youngs_modulus(const Lame& p);

/// "mu=1 lambda=10 (nu=0.4545)": for messages and tables.
[[nodiscard]] std::string describe(const Lame& p);

}  // namespace snh
