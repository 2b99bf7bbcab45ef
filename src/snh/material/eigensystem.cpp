#include "snh/material/eigensystem.hpp"

#include <cmath>

namespace snh {

namespace {

/// The SVD frame's basis of 9-vectors: columns 0..2 twist k = (u_b v_aᵀ − u_a v_bᵀ)/√2, 3..5 flip k
/// (the same with +), 6..8 vec(u_k v_kᵀ), with (a, b) the two axes other than k (docs/math.md §4).
Mat9 frame_basis(const Svd3& svd) {
  const Mat3& U = svd.U;
  const Mat3& V = svd.V;
  const double r = std::sqrt(0.5);
  Mat9 basis;
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const Mat3 ba = U.col(b) * V.col(a).transpose();
    const Mat3 ab = U.col(a) * V.col(b).transpose();
    basis.col(k) = vec(r * (ba - ab));
    basis.col(3 + k) = vec(r * (ba + ab));
    basis.col(6 + k) = vec(U.col(k) * V.col(k).transpose());
  }
  return basis;
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
  const bool positive_definite = A(0, 0) > 0.0 && A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1) > 0.0 && A.determinant() > 0.0;
  if (p == PsdProjection::none || positive_definite) {
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

namespace {

/// slices += c vec(M) vec(M)ᵀ: slice (i, k) gains c (row i of M)ᵀ (row k of M).
void add_outer(const Mat3& M, double c, HessianSlices& slices) {
  for (int i = 0; i < 3; ++i) {
    const Vec3 ci = c * M.row(i).transpose();
    for (int k = 0; k <= i; ++k) slices[static_cast<std::size_t>(i * (i + 1) / 2 + k)].noalias() += ci * M.row(k);
  }
}

}  // namespace

int add_projection_change(const Svd3& svd, const SigmaEigenvalues& s, PsdProjection p, double w, HessianSlices& slices) {
  if (p == PsdProjection::none) return 0;
  const Mat3& U = svd.U;
  const Mat3& V = svd.V;
  int changed = 0;
  const double r = std::sqrt(0.5);
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double dt = project_eigenvalue(s.twist[k], p) - s.twist[k], df = project_eigenvalue(s.flip[k], p) - s.flip[k];
    if (dt == 0.0 && df == 0.0) continue;
    const Mat3 ba = U.col(b) * V.col(a).transpose(), ab = U.col(a) * V.col(b).transpose();
    if (dt != 0.0) {
      add_outer(r * (ba - ab), w * dt, slices);
      ++changed;
    }
    if (df != 0.0) {
      add_outer(r * (ba + ab), w * df, slices);
      ++changed;
    }
  }
  const Mat3& A = s.A;
  if (A(0, 0) > 0.0 && A(0, 0) * A(1, 1) - A(0, 1) * A(0, 1) > 0.0 && A.determinant() > 0.0) return changed;
  const SymEigen3 e = symmetric_eigen3(A);
  for (int k = 0; k < 3; ++k) {
    const double d = project_eigenvalue(e.values[k], p) - e.values[k];
    if (d == 0.0) continue;
    // The scaling eigenvector vec(U diag(q) Vᵀ), q the eigenvector of A.
    add_outer(U * e.vectors.col(k).asDiagonal() * V.transpose(), w * d, slices);
    ++changed;
  }
  return changed;
}

}  // namespace snh
