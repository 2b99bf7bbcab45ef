#include "snh/material/eigensystem.hpp"

#include <cmath>

namespace snh {

namespace {

/// Twist k and flip k as 3x3 matrices, (u_b v_aᵀ ∓ u_a v_bᵀ)/√2 with (a, b) the two axes other than k.
struct TwistFlip {
  Mat3 twist, flip;
};
TwistFlip twist_flip(const Svd3& svd, int k) {
  const double r = std::sqrt(0.5);
  const int a = (k + 1) % 3, b = (k + 2) % 3;
  const Mat3 ba = svd.U.col(b) * svd.V.col(a).transpose();
  const Mat3 ab = svd.U.col(a) * svd.V.col(b).transpose();
  return {r * (ba - ab), r * (ba + ab)};
}

/// Whether the symmetric A is positive definite (Sylvester's criterion: its leading minors are positive).
bool positive_definite(const Mat3& A) {
  return A(0, 0) > 0.0 && A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1) > 0.0 && A.determinant() > 0.0;
}

/// The SVD frame's basis of 9-vectors: columns 0..2 twist k, 3..5 flip k, 6..8 vec(u_k v_kᵀ) (docs/math.md §4).
Mat9 frame_basis(const Svd3& svd) {
  Mat9 basis;
  for (int k = 0; k < 3; ++k) {
    const TwistFlip tf = twist_flip(svd, k);
    basis.col(k) = vec(tf.twist);
    basis.col(3 + k) = vec(tf.flip);
    basis.col(6 + k) = vec(svd.U.col(k) * svd.V.col(k).transpose());
  }
  return basis;
}

/// slices += c vec(M) vec(M)ᵀ: slice (i, k) gains c (row i of M)ᵀ (row k of M).
void add_outer(const Mat3& M, double c, HessianSlices& slices) {
  for (int i = 0; i < 3; ++i) {
    const Vec3 ci = c * M.row(i).transpose();
    for (int k = 0; k <= i; ++k) slices[static_cast<std::size_t>(i * (i + 1) / 2 + k)].noalias() += ci * M.row(k);
  }
}

}  // namespace

Eigensystem9 assemble_eigensystem(const Svd3& svd, const SigmaEigenvalues& s) {
  Eigensystem9 es;
  const Mat9 basis = frame_basis(svd);
  es.vectors.leftCols<6>() = basis.leftCols<6>();
  for (int k = 0; k < 3; ++k) {
    es.values[k] = s.twist[k];
    es.values[3 + k] = s.flip[k];
  }
  // Scaling eigenvector U diag(e) Vᵀ = Σ_i e_i vec(u_i v_iᵀ).
  const SymEigen3 scaling = symmetric_eigen3(s.A);
  es.vectors.rightCols<3>() = basis.rightCols<3>() * scaling.vectors;
  for (int k = 0; k < 3; ++k) es.values[6 + k] = scaling.values[k];
  return es;
}

Mat9 rebuild(const Eigensystem9& es, PsdProjection p) {
  Vec9 d;
  for (int i = 0; i < 9; ++i) d[i] = project_eigenvalue(es.values[i], p);
  return es.vectors * d.asDiagonal() * es.vectors.transpose();
}

Mat9 projected_from_sigma(const Svd3& svd, const SigmaEigenvalues& s, PsdProjection p) {
  const Mat9 basis = frame_basis(svd);
  const auto W = basis.leftCols<6>();   // twist 0..2, flip 0..2
  const auto D = basis.rightCols<3>();  // vec(u_i v_iᵀ)
  Eigen::Matrix<double, 1, 6> d;
  for (int k = 0; k < 3; ++k) {
    d[k] = project_eigenvalue(s.twist[k], p);
    d[3 + k] = project_eigenvalue(s.flip[k], p);
  }
  const Mat3& A = s.A;
  Mat3 Ap;
  if (p == PsdProjection::none || positive_definite(A)) {
    Ap = A;
  } else {
    const SymEigen3 e = symmetric_eigen3(A);
    Vec3 ev;
    for (int k = 0; k < 3; ++k) ev[k] = project_eigenvalue(e.values[k], p);
    Ap = e.vectors * ev.asDiagonal() * e.vectors.transpose();
  }
  const Eigen::Matrix<double, 9, 6> Wd = W * d.asDiagonal();
  const Eigen::Matrix<double, 9, 3> DA = D * Ap;
  // Coefficient-based products: at these small fixed sizes (9x6, 9x3) they beat Eigen's blocked GEMM, whose
  // packing costs more than the arithmetic (bench_material).
  Mat9 H = Wd.lazyProduct(W.transpose());
  H.noalias() += DA.lazyProduct(D.transpose());
  return H;
}

int add_projection_change(const Svd3& svd, const SigmaEigenvalues& s, PsdProjection p, double w, HessianSlices& slices) {
  if (p == PsdProjection::none) return 0;
  int changed = 0;
  for (int k = 0; k < 3; ++k) {
    const double dt = project_eigenvalue(s.twist[k], p) - s.twist[k], df = project_eigenvalue(s.flip[k], p) - s.flip[k];
    if (dt == 0.0 && df == 0.0) continue;
    const TwistFlip tf = twist_flip(svd, k);
    if (dt != 0.0) {
      add_outer(tf.twist, w * dt, slices);
      ++changed;
    }
    if (df != 0.0) {
      add_outer(tf.flip, w * df, slices);
      ++changed;
    }
  }
  if (positive_definite(s.A)) return changed;
  const SymEigen3 e = symmetric_eigen3(s.A);
  for (int k = 0; k < 3; ++k) {
    const double d = project_eigenvalue(e.values[k], p) - e.values[k];
    if (d == 0.0) continue;
    // The scaling eigenvector vec(U diag(q) Vᵀ), q the eigenvector of A.
    add_outer(svd.U * e.vectors.col(k).asDiagonal() * svd.V.transpose(), w * d, slices);
    ++changed;
  }
  return changed;
}

}  // namespace snh
