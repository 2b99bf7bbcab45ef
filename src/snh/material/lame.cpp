#include "snh/material/lame.hpp"

#include <cmath>

#include <fmt/format.h>

namespace snh {

void validate(const Lame& p) {
  if (!std::isfinite(p.mu) || p.mu <= 0.0)
    throw ParameterError(fmt::format("mu must be a finite number > 0, got {}", p.mu));
  if (!std::isfinite(p.lambda))
    throw ParameterError(fmt::format("lambda must be a finite number, got {}", p.lambda));
  if (p.mu < kMinModulus || p.mu > kMaxModulus)
    throw ParameterError(fmt::format("mu = {:g} is outside the supported range [{:g}, {:g}]", p.mu, kMinModulus,
                                     kMaxModulus));
  if (p.lambda != 0.0 && (std::abs(p.lambda) < kMinModulus || std::abs(p.lambda) > kMaxModulus))
    throw ParameterError(fmt::format("lambda = {:g} is outside the supported range (0 or |lambda| in [{:g}, {:g}])",
                                     p.lambda, kMinModulus, kMaxModulus));
  if (p.lambda + 2.0 * p.mu / 3.0 <= 0.0)
    throw ParameterError(fmt::format(
        "lambda = {} with mu = {} gives a non-positive bulk modulus (need lambda > -2mu/3, i.e. nu > -1)",
        p.lambda, p.mu));
}

Lame lame_from_youngs(double youngs, double poisson) {
  if (!std::isfinite(youngs) || youngs <= 0.0)
    throw ParameterError(fmt::format("Young's modulus must be a finite number > 0, got {}", youngs));
  if (!std::isfinite(poisson) || poisson <= -1.0 || poisson >= 0.5)
    throw ParameterError(
        fmt::format("Poisson's ratio must satisfy -1 < nu < 0.5, got {}", poisson));
  const Lame p{youngs / (2.0 * (1.0 + poisson)),
               youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))};
  validate(p);
  return p;
}

double poisson_ratio(const Lame& p) { return p.lambda / (2.0 * (p.lambda + p.mu)); }

double youngs_modulus(const Lame& p) {
  return p.mu * (3.0 * p.lambda + 2.0 * p.mu) / (p.lambda + p.mu);
}

std::string describe(const Lame& p) {
  return fmt::format("mu={:g} lambda={:g} (nu={:.4f})", p.mu, p.lambda, poisson_ratio(p));
}

}  // namespace snh
