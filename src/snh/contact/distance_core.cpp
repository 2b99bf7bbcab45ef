#include "snh/contact/distance_core.hpp"

namespace snh::contact {
namespace {

/// q = w²/m from w, m and their derivatives (the quotient and product rules):
///   ∇q  = (2w/m)∇w − (w²/m²)∇m
///   ∇²q = (2/m)∇w∇wᵀ + (2w/m)∇²w − (2w/m²)(∇w∇mᵀ + ∇m∇wᵀ) − (w²/m²)∇²m + (2w²/m³)∇m∇mᵀ
template <int N>
Derivatives<N> square_over(const Derivatives<N>& w, const Derivatives<N>& m) {
  const double W = w.value, M = m.value;
  Derivatives<N> q;
  q.value = W * W / M;
  q.gradient = (2.0 * W / M) * w.gradient - (W * W / (M * M)) * m.gradient;
  const MatN<N> cross = w.gradient * m.gradient.transpose();
  q.hessian = (2.0 / M) * w.gradient * w.gradient.transpose() + (2.0 * W / M) * w.hessian -
              (2.0 * W / (M * M)) * (cross + cross.transpose()) - (W * W / (M * M)) * m.hessian +
              (2.0 * W * W / (M * M * M)) * m.gradient * m.gradient.transpose();
  return q;
}

/// The Hessian over (a, b) of c·(a × b) for a fixed c: ∂²/∂a∂b = −[c]×, ∂²/∂b∂a = [c]× (c·(a×b) = aᵀ[b]×c
/// = −aᵀ[c]×b), the diagonal blocks zero.
Mat6 triple_product_hessian(const Vec3& c) {
  Mat6 H = Mat6::Zero();
  H.block<3, 3>(0, 3) = -cross_matrix(c);
  H.block<3, 3>(3, 0) = cross_matrix(c);
  return H;
}

}  // namespace

Derivatives<3> squared_norm_derivatives(const Vec3& u) {
  Derivatives<3> f;
  f.value = u.squaredNorm();
  f.gradient = 2.0 * u;
  f.hessian = 2.0 * Mat3::Identity();
  return f;
}

Derivatives<6> cross_squared_norm(const Vec3& a, const Vec3& b) {
  // m = n·n with n = a×b; ∂n/∂a = −[b]×, ∂n/∂b = [a]× (the 3×6 matrix Nn), so
  // ∇m = 2 Nnᵀ n = (2 b×n, 2 n×a) and ∇²m = 2 NnᵀNn + 2 ∇²(n̄·(a×b)) with n̄ = n held fixed.
  const Vec3 n = a.cross(b);
  Eigen::Matrix<double, 3, 6> Nn;
  Nn << -cross_matrix(b), cross_matrix(a);
  Derivatives<6> m;
  m.value = n.squaredNorm();
  m.gradient = 2.0 * Nn.transpose() * n;
  m.hessian = 2.0 * Nn.transpose() * Nn + 2.0 * triple_product_hessian(n);
  return m;
}

Derivatives<6> point_line_core(const Vec3& u, const Vec3& v) {
  // f = |u|² − s²/m with s = u·v (∇s = (v, u), ∇²s = [[0, I], [I, 0]]) and m = v·v (∇m = (0, 2v),
  // ∇²m = diag(0, 2I)).
  Derivatives<6> s, m;
  s.value = u.dot(v);
  s.gradient << v, u;
  s.hessian.block<3, 3>(0, 3) = Mat3::Identity();
  s.hessian.block<3, 3>(3, 0) = Mat3::Identity();
  m.value = v.squaredNorm();
  m.gradient << Vec3::Zero(), 2.0 * v;
  m.hessian.block<3, 3>(3, 3) = 2.0 * Mat3::Identity();
  Derivatives<6> f = square_over(s, m);
  f.value = u.cross(v).squaredNorm() / m.value;  // = |u|² − s²/m, without its cancellation
  f.gradient = -f.gradient;
  f.gradient.head<3>() += 2.0 * u;
  f.hessian = -f.hessian;
  f.hessian.block<3, 3>(0, 0) += 2.0 * Mat3::Identity();
  return f;
}

Derivatives<9> point_plane_core(const Vec3& u, const Vec3& a, const Vec3& b) {
  // f = w²/m with w = u·(a×b): ∇w = (a×b, b×u, u×a); ∇²w has the (u, a) block −[b]×, (u, b) [a]×, their
  // transposes, and over (a, b) the triple-product Hessian of u. m = |a×b|² does not depend on u.
  const Derivatives<6> n2 = cross_squared_norm(a, b);
  Derivatives<9> w, m;
  w.value = u.dot(a.cross(b));
  w.gradient.segment<3>(0) = a.cross(b);
  w.gradient.segment<3>(3) = b.cross(u);
  w.gradient.segment<3>(6) = u.cross(a);
  w.hessian.block<3, 3>(0, 3) = -cross_matrix(b);
  w.hessian.block<3, 3>(0, 6) = cross_matrix(a);
  w.hessian.block<3, 3>(3, 0) = cross_matrix(b);
  w.hessian.block<3, 3>(6, 0) = -cross_matrix(a);
  w.hessian.block<6, 6>(3, 3) = triple_product_hessian(u);
  m.value = n2.value;
  m.gradient.tail<6>() = n2.gradient;
  m.hessian.block<6, 6>(3, 3) = n2.hessian;
  return square_over(w, m);
}

}  // namespace snh::contact
