#pragma once
// The smooth squared distances IPC's closest-feature pairs reduce to, written on difference vectors
// (u = x_i − x_j) with exact gradients and Hessians, and the chain rule back to the pair's points.
//   point–point   f(u)       = |u|²
//   point–line    f(u, v)    = |u|² − (u·v)²/|v|²          (u from a point of the line, v its direction)
//   point–plane   f(u, a, b) = (u·n)²/|n|²,  n = a × b     (also line–line: a, b the two directions)
// Each is a composition of dot products, so its Hessian follows from the product and quotient rules
// (derivations in the .cpp, next to each formula).
#include <array>
#include <utility>

#include "snh/math/types.hpp"

namespace snh::contact {

template <int N>
using VecN = Eigen::Matrix<double, N, 1>;
template <int N>
using MatN = Eigen::Matrix<double, N, N>;
using Vec6 = VecN<6>;
using Vec12 = VecN<12>;
using Mat6 = MatN<6>;
using Mat12 = MatN<12>;

/// A scalar of N variables with its gradient and Hessian.
template <int N>
struct Derivatives {
  double value = 0.0;
  VecN<N> gradient = VecN<N>::Zero();
  MatN<N> hessian = MatN<N>::Zero();
};

/// |u|²: gradient 2u, Hessian 2I.
[[nodiscard]] Derivatives<3> squared_norm_derivatives(const Vec3& u);

/// |u|² − (u·v)²/|v|² over (u, v): the squared distance from a point at offset u from a point of a line
/// with direction v ≠ 0 to that line.
[[nodiscard]] Derivatives<6> point_line_core(const Vec3& u, const Vec3& v);

/// (u·(a×b))²/|a×b|² over (u, a, b): the squared distance from a point at offset u to the plane spanned
/// by a and b (a × b ≠ 0); also the squared distance between two lines with directions a and b whose
/// points differ by u.
[[nodiscard]] Derivatives<9> point_plane_core(const Vec3& u, const Vec3& a, const Vec3& b);

/// |a×b|² over (a, b): the squared norm of the cross product (the edge–edge mollifier's argument).
[[nodiscard]] Derivatives<6> cross_squared_norm(const Vec3& a, const Vec3& b);

/// Which points a difference vector subtracts: {i, j} means u = x_i − x_j.
using Difference = std::pair<int, int>;

/// The chain rule from K difference vectors to M points: for u_k = x_{i_k} − x_{j_k},
/// ∇ₓf = Jᵀ∇f and ∇ₓ²f = Jᵀ∇²f J with J the (3K × 3M) matrix of ±I blocks.
template <int K, std::size_t M>
[[nodiscard]] Derivatives<3 * M> pull_back(const Derivatives<3 * K>& f, const std::array<Difference, K>& diffs) {
  // J as K rows of M blocks, each block +1, −1 or 0 times I (the same for every coordinate).
  Eigen::Matrix<double, K, int(M)> S = Eigen::Matrix<double, K, int(M)>::Zero();
  for (int k = 0; k < K; ++k) {
    S(k, diffs[k].first) += 1.0;
    S(k, diffs[k].second) -= 1.0;
  }
  Derivatives<3 * M> out;
  out.value = f.value;
  for (int m = 0; m < int(M); ++m)
    for (int k = 0; k < K; ++k)
      if (S(k, m) != 0.0) out.gradient.template segment<3>(3 * m) += S(k, m) * f.gradient.template segment<3>(3 * k);
  for (int m = 0; m < int(M); ++m)
    for (int n = 0; n < int(M); ++n)
      for (int k = 0; k < K; ++k)
        for (int l = 0; l < K; ++l)
          if (S(k, m) != 0.0 && S(l, n) != 0.0)
            out.hessian.template block<3, 3>(3 * m, 3 * n) +=
                S(k, m) * S(l, n) * f.hessian.template block<3, 3>(3 * k, 3 * l);
  return out;
}

/// The four pieces on M points x (indices into x), as values and as derivatives over all 3M coordinates.
///   point_point  |x_i − x_j|²
///   point_line   squared distance from x_p to the line through x_l0, x_l1
///   point_plane  squared distance from x_p to the plane through x_a0, x_a1, x_a2
///   line_line    squared distance between the lines through x_a0, x_a1 and through x_b0, x_b1
/// The values are computed in the forms least prone to cancellation (|u×v|²/|v|² for the line).
template <std::size_t M>
using Points = std::array<Vec3, M>;

template <std::size_t M>
[[nodiscard]] double point_point_value(const Points<M>& x, int i, int j) {
  return (x[i] - x[j]).squaredNorm();
}
template <std::size_t M>
[[nodiscard]] double point_line_value(const Points<M>& x, int p, int l0, int l1) {
  const Vec3 v = x[l1] - x[l0];
  return (x[p] - x[l0]).cross(v).squaredNorm() / v.squaredNorm();
}
template <std::size_t M>
[[nodiscard]] double point_plane_value(const Points<M>& x, int p, int a0, int a1, int a2) {
  const Vec3 n = (x[a1] - x[a0]).cross(x[a2] - x[a0]);
  const double w = (x[p] - x[a0]).dot(n);
  return w * w / n.squaredNorm();
}
template <std::size_t M>
[[nodiscard]] double line_line_value(const Points<M>& x, int a0, int a1, int b0, int b1) {
  const Vec3 n = (x[a1] - x[a0]).cross(x[b1] - x[b0]);
  const double w = (x[b0] - x[a0]).dot(n);
  return w * w / n.squaredNorm();
}

template <std::size_t M>
[[nodiscard]] Derivatives<3 * M> point_point_piece(const Points<M>& x, int i, int j) {
  return pull_back<1, M>(squared_norm_derivatives(x[i] - x[j]), {Difference{i, j}});
}
template <std::size_t M>
[[nodiscard]] Derivatives<3 * M> point_line_piece(const Points<M>& x, int p, int l0, int l1) {
  return pull_back<2, M>(point_line_core(x[p] - x[l0], x[l1] - x[l0]), {Difference{p, l0}, Difference{l1, l0}});
}
template <std::size_t M>
[[nodiscard]] Derivatives<3 * M> point_plane_piece(const Points<M>& x, int p, int a0, int a1, int a2) {
  return pull_back<3, M>(point_plane_core(x[p] - x[a0], x[a1] - x[a0], x[a2] - x[a0]),
                         {Difference{p, a0}, Difference{a1, a0}, Difference{a2, a0}});
}
template <std::size_t M>
[[nodiscard]] Derivatives<3 * M> line_line_piece(const Points<M>& x, int a0, int a1, int b0, int b1) {
  return pull_back<3, M>(point_plane_core(x[b0] - x[a0], x[a1] - x[a0], x[b1] - x[b0]),
                         {Difference{b0, a0}, Difference{a1, a0}, Difference{b1, b0}});
}

}  // namespace snh::contact
