#pragma once
// The edge–edge mollifier (IPC, Li et al. 2020, §4.3): near-parallel edges make the edge–edge distance
// lose smoothness (its type switches between the line–line piece and endpoint pieces), so the edge–edge
// barrier is multiplied by a factor that goes smoothly to 0 as the edges become parallel.
//   x = |(ea1 − ea0) × (eb1 − eb0)|²
//   m(x) = (2 − x/ε)·x/ε  for x < ε,   1 for x ≥ ε      (C¹ at x = ε: m = 1, m' = 0)
//   ε = 1e-3 · |ea1 − ea0|² · |eb1 − eb0|², from the REST positions (a constant of the pair)
// Derivatives over (ea0, ea1, eb0, eb1): ∇m = m'(x)∇x, ∇²m = m''(x)∇x∇xᵀ + m'(x)∇²x, with m' = 2/ε − 2x/ε²
// and m'' = −2/ε² below ε (0 above).
#include "snh/contact/distance_core.hpp"

namespace snh::contact {

/// ε = 1e-3 |ea1 − ea0|² |eb1 − eb0|² of the rest positions.
[[nodiscard]] double edge_edge_mollifier_threshold(const Vec3& ea0_rest, const Vec3& ea1_rest, const Vec3& eb0_rest,
                                                   const Vec3& eb1_rest);

/// m(x) with x = |(ea1 − ea0) × (eb1 − eb0)|²; threshold is ε (> 0).
[[nodiscard]] double edge_edge_mollifier(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                         double threshold);
[[nodiscard]] Derivatives<12> edge_edge_mollifier_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0,
                                                              const Vec3& eb1, double threshold);

}  // namespace snh::contact
