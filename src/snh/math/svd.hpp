#pragma once
// Rotation-variant singular value decomposition of a 3x3 matrix (docs/math.md §4).
#include "snh/math/types.hpp"

namespace snh {

/// F = U diag(sigma) Vᵀ with det U = det V = +1 and σ0 ≥ σ1 ≥ |σ2|. A reflection (det F < 0)
/// is carried as a negative sign on the smallest singular value σ2.
struct Svd3 {
  Mat3 U;      ///< rotation, det U = +1
  Vec3 sigma;  ///< signed singular values, descending in magnitude
  Mat3 V;      ///< rotation, det V = +1
  /// U diag(sigma) Vᵀ.
  [[nodiscard]] Mat3 reconstruct() const { return U * sigma.asDiagonal() * V.transpose(); }
};

/// Rotation-variant SVD by one-sided (Hestenes) Jacobi on the columns of F, then a completion of U
/// that stays orthonormal for rank-deficient F (zero, rank 1, rank 2). Accurate to a few ulps of ‖F‖
/// in reconstruction; robust for repeated, zero, tiny and negative singular values.
///   F  3x3 input; for a non-finite entry the result is U = V = I and σ = NaN (so callers see it)
[[nodiscard]] Svd3 rotation_variant_svd(const Mat3& F);

/// The same decomposition with the negative sign (when det F < 0) moved from σ2 to σ_k.
/// Still a valid rotation-variant SVD of the same F (U is changed by a rotation of π about axis
/// j ≠ k). Used to test that energies do not depend on where the reflection is carried (docs/math.md §5.2).
///   svd  a decomposition from rotation_variant_svd
///   k    0, 1 or 2: which singular value should carry the sign
[[nodiscard]] Svd3 move_reflection(const Svd3& svd, int k);

/// Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations: A = Q diag(values) Qᵀ,
/// Q orthonormal. Accurate to a few ulps of ‖A‖ for any symmetric A (repeated eigenvalues included).
struct SymEigen3 {
  Vec3 values;
  Mat3 vectors;  ///< columns are the eigenvectors
};
[[nodiscard]] SymEigen3 symmetric_eigen3(const Mat3& A);

}  // namespace snh
