#pragma once
// Continuous collision detection over a linear step: each of the four points moves from x to x + t·dx,
// t ∈ [0, 1]. Returns the largest fraction t of the step known to be free of contact, with a separation
// kept: the distance at the returned t is at least options.keep times the distance at t = 0.
//
// The method is additive CCD (Li, Kaufman, Jiang, "Codimensional Incremental Potential Contact", SIGGRAPH
// 2021, §5): with the displacements made relative (their mean subtracted: a common translation does not
// change distances), l = |dp_max| + |dq_max| bounds how fast the distance d between the two primitives can
// shrink per unit t (the point's speed plus the fastest vertex of the other primitive; for two edges the
// fastest vertex of each), so advancing t by 0.9·d/l can at most shrink d to a tenth of itself: never to 0.
// It is chosen over root finding of the coplanarity cubic because it cannot miss a root to rounding (its
// only floating-point step is a distance, computed stably) and needs no tolerance tuned to the scene.
//   t = 0; first advance (1 − keep)·d₀/l (the distance stays ≥ keep·d₀ by the bound alone);
//   then repeat: advance by 0.9·d/l to t'; if d(t') < keep·d₀ return t (the last safe time, not t');
//   if t' ≥ 1 return 1 (the whole rest of the step moves less than 0.9·d: no contact).
// Properties: never returns 0 for a separated start (d₀ > 0): the first advance is always taken;
// never misses: every advanced interval [t, t + 0.9 d/l] keeps the distance ≥ d/10 > 0 (up to the
// rounding of the computed distance, far below keep·d₀ unless d₀ is at rounding level itself).
// Touching or overlapping at t = 0 (d₀ = 0) returns 0; no relative motion returns 1.
// Iterations are bounded by options.max_iterations: past it the current (safe, possibly small) t is returned.
// Non-finite positions or displacements, or keep outside (0, 1), throw std::invalid_argument (one line).
#include "snh/math/types.hpp"

namespace snh::contact {

struct CcdOptions {
  double keep = 0.1;                   ///< the fraction of the starting distance kept at the returned t
  long max_iterations = 1'000'000;     ///< safety bound on the loop (each iteration is one distance)
};

/// Point p (moving by dp) against triangle (t0, t1, t2) (moving by dt0, dt1, dt2).
[[nodiscard]] double point_triangle_ccd(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                        const Vec3& dp, const Vec3& dt0, const Vec3& dt1, const Vec3& dt2,
                                        const CcdOptions& options = {});

/// Segment (ea0, ea1) (moving by dea0, dea1) against segment (eb0, eb1) (moving by deb0, deb1).
[[nodiscard]] double edge_edge_ccd(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                   const Vec3& dea0, const Vec3& dea1, const Vec3& deb0, const Vec3& deb1,
                                   const CcdOptions& options = {});

}  // namespace snh::contact
