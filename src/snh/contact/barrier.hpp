#pragma once
// IPC's log barrier (Li et al. 2020, §4.1):  b(d, d̂) = −(d − d̂)² ln(d / d̂)  for 0 < d < d̂,  0 for d ≥ d̂.
// Convention (IPC Toolkit's): the arguments are SQUARED distances, s = d² and ŝ = d̂², so the barrier
// is b(s, ŝ) and a pair is active when its unsigned distance is below d̂; the contact energy of a pair is
// κ·b(s(x), ŝ) (times the mollifier for edge–edge pairs), and its derivatives over the pair's positions
// follow by the chain rule: ∇ = b'∇s, ∇² = b''∇s∇sᵀ + b'∇²s.
//   b'(s)  = −2(s − ŝ) ln(s/ŝ) − (s − ŝ)²/s
//   b''(s) = −2 ln(s/ŝ) − 4(s − ŝ)/s + (s − ŝ)²/s²
// b, b' and b'' are 0 at s = ŝ (b is C² there) and b → +∞ as s → 0⁺; b ≥ 0, b' ≤ 0, b'' > 0 on (0, ŝ).
// At s ≤ 0 (contact or interpenetration, which CCD keeps out): b = +∞, b' = −∞, b'' = +∞.
// ŝ must be > 0 (not checked here: the caller validates d̂ once).
namespace snh::contact {

[[nodiscard]] double barrier(double s, double s_hat);
[[nodiscard]] double barrier_first_derivative(double s, double s_hat);
[[nodiscard]] double barrier_second_derivative(double s, double s_hat);

}  // namespace snh::contact
