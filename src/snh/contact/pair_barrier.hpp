#pragma once
// The barrier energy of one contact pair over its 12 coordinates, what a contact term sums (times κ) and
// scatters through the pair's vertex ids (IPC, Li et al. 2020, §4):
//   point–triangle (p, t0, t1, t2):       B = b(s(x), ŝ)
//   edge–edge (ea0, ea1, eb0, eb1):       B = m(x)·b(s(x), ŝ)     (m the mollifier, edge_edge_mollifier.hpp)
// with s the squared distance of the pair's type at x (distance_type.hpp) and ŝ = d̂². Chain and product
// rules:  ∇(b∘s) = b'∇s,  ∇²(b∘s) = b''∇s∇sᵀ + b'∇²s;  ∇(m·b) = m∇b + b∇m,  ∇²(m·b) = m∇²b + ∇m∇bᵀ + ∇b∇mᵀ
// + b∇²m. With project, the Hessian is made PSD (project_psd.hpp) for Newton. A pair at s ≥ ŝ gives
// exactly 0 (value, gradient, Hessian); at s ≤ 0 the value is +∞ (CCD keeps iterates away from it), and
// at non-finite positions NaN (the derivatives then 0): a line search rejects either.
#include "snh/contact/barrier.hpp"
#include "snh/contact/distance_core.hpp"

namespace snh::contact {

/// scale · b∘s from the derivatives of a squared distance s (0 < s.value < ŝ): the chain rule above, over the
/// pair's N coordinates (for a contact term's point–point, point–edge and point–triangle pairs as well).
template <int N>
[[nodiscard]] Derivatives<N> barrier_of(const Derivatives<N>& s, double s_hat, double scale = 1.0) {
  Derivatives<N> b;
  const double b1 = barrier_first_derivative(s.value, s_hat);
  b.value = scale * barrier(s.value, s_hat);
  b.gradient = (scale * b1) * s.gradient;
  b.hessian = scale * (barrier_second_derivative(s.value, s_hat) * s.gradient * s.gradient.transpose() + b1 * s.hessian);
  return b;
}

[[nodiscard]] Derivatives<12> point_triangle_barrier(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                                     double s_hat, bool project);

/// mollifier_threshold: ε of edge_edge_mollifier_threshold at the rest positions.
[[nodiscard]] Derivatives<12> edge_edge_barrier(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                                double s_hat, double mollifier_threshold, bool project);

}  // namespace snh::contact
