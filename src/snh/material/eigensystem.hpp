#pragma once
// The 9x9 eigensystem of an isotropic energy's ∂P/∂F in the rotation-variant SVD frame (docs/math.md §4).
#include <array>
#include <string_view>

#include "snh/material/psd_projection.hpp"
#include "snh/math/svd.hpp"
#include "snh/math/types.hpp"

namespace snh {

/// Eigenvalues in the σ frame before the 3x3 scaling block is diagonalised:
/// twist[k] and flip[k] belong to the pair of axes other than k; A is the 3x3 scaling block
/// (the Hessian of ψ̂ with respect to the signed singular values).
struct SigmaEigenvalues {
  Vec3 twist;
  Vec3 flip;
  Mat3 A;
};

/// Nine eigenvalues and orthonormal eigenvectors (columns of `vectors`, each a vec'd 3x3 matrix).
/// Order: twist 0..2, flip 0..2, scaling 0..2.
struct Eigensystem9 {
  std::array<double, 9> values{};
  Mat9 vectors = Mat9::Zero();
};

inline constexpr std::array<std::string_view, 9> kEigenLabels = {
    "twist_0", "twist_1", "twist_2", "flip_0", "flip_1", "flip_2", "scaling_0", "scaling_1", "scaling_2"};

/// Builds the eigensystem from the SVD of F and the σ-frame eigenvalues (docs/math.md §4):
/// twist k = (u_b v_aᵀ − u_a v_bᵀ)/√2, flip k = (u_b v_aᵀ + u_a v_bᵀ)/√2 with (a, b) the other two axes,
/// scaling = U diag(e) Vᵀ for each eigenvector e of A.
[[nodiscard]] Eigensystem9 assemble_eigensystem(const Svd3& svd, const SigmaEigenvalues& s);

/// Σ f(λ_i) q_i q_iᵀ with f the chosen projection (none gives back the Hessian itself).
[[nodiscard]] Mat9 rebuild(const Eigensystem9& es, PsdProjection p);

/// The same matrix as rebuild(assemble_eigensystem(svd, s), p), computed without diagonalising the
/// scaling block when it is already positive definite: with W the six twist/flip vectors and
/// D = [vec(u_i v_iᵀ)], H = W diag(f(twist, flip)) Wᵀ + D f(A) Dᵀ, and f(A) = A when A ≻ 0
/// (Sylvester's criterion), else Q diag(f(λ)) Qᵀ from symmetric_eigen3(A).
[[nodiscard]] Mat9 projected_from_sigma(const Svd3& svd, const SigmaEigenvalues& s, PsdProjection p);

/// ∂P/∂F kept as its six 3x3 slices: slices[i(i+1)/2 + k](j, l) = H(3j+i, 3l+k) for i ≥ k (vec is column-major,
/// vec(F)_{3j+i} = F(i, j)), the form in which an invariant energy gives its Hessian (weighted_hessian_slices).
using HessianSlices = std::array<Mat3, 6>;

/// Adds w (f(H) − H) to the slices of w H, H the Hessian whose eigensystem the SVD of F and the σ-frame
/// eigenvalues s give (f the projection): w (f(λ) − λ) q qᵀ for each eigenpair (λ, q) that f changes, that is
/// each negative eigenvalue; a scaling block that is positive definite (Sylvester's criterion) has none and is
/// not diagonalised. The projected Hessian is then the analytic one plus a correction of rank at most 9
/// (usually none), without building the 9x9 matrix. Returns how many eigenvalues were changed.
int add_projection_change(const Svd3& svd, const SigmaEigenvalues& s, PsdProjection p, double w, HessianSlices& slices);

}  // namespace snh
