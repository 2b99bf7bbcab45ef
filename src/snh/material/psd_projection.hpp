#pragma once
// How a Hessian's negative eigenvalues are treated before it is used as a Newton matrix (docs/math.md §4).
#include <optional>
#include <string_view>

namespace snh {

enum class PsdProjection {
  none,   ///< keep the eigenvalues as they are (the true Hessian)
  clamp,  ///< replace negative eigenvalues by zero
  abs,    ///< replace each eigenvalue by its absolute value
};

[[nodiscard]] constexpr std::string_view to_string(PsdProjection p) {
  switch (p) {
    case PsdProjection::none: return "none";
    case PsdProjection::clamp: return "clamp";
    case PsdProjection::abs: return "abs";
  }
  return "?";
}

/// Parses "none", "clamp" or "abs"; nullopt for anything else.
[[nodiscard]] constexpr std::optional<PsdProjection> parse_projection(std::string_view s) {
  if (s == "none") return PsdProjection::none;
  if (s == "clamp") return PsdProjection::clamp;
  if (s == "abs") return PsdProjection::abs;
  return std::nullopt;
}

/// The projected value of one eigenvalue.
[[nodiscard]] constexpr double project_eigenvalue(double value, PsdProjection p) {
  switch (p) {
    case PsdProjection::none: return value;
    case PsdProjection::clamp: return value > 0.0 ? value : 0.0;
    case PsdProjection::abs: return value >= 0.0 ? value : -value;
  }
  return value;
}

}  // namespace snh
