#include "snh/contact/project_psd.hpp"

// This file is compiled with -Wno-uninitialized (src/CMakeLists.txt): GCC 12 with -march=native warns
// falsely inside Eigen's 12×12 SelfAdjointEigenSolver (an AVX-512 max over a reduction's unused lanes).
namespace snh::contact {
namespace {

template <int N>
MatN<N> clamp_eigenvalues(const MatN<N>& H) {
  const MatN<N> symmetric = 0.5 * (H + H.transpose());
  const Eigen::SelfAdjointEigenSolver<MatN<N>> eig(symmetric);
  VecN<N> lambda = eig.eigenvalues();
  if (lambda[0] >= 0.0) return symmetric;  // sorted ascending: already PSD
  for (int i = 0; i < N; ++i) lambda[i] = lambda[i] > 0.0 ? lambda[i] : 0.0;
  const MatN<N> Q = eig.eigenvectors();
  return Q * lambda.asDiagonal() * Q.transpose();
}

}  // namespace

Mat6 project_psd(const Mat6& H) { return clamp_eigenvalues<6>(H); }
MatN<9> project_psd(const MatN<9>& H) { return clamp_eigenvalues<9>(H); }
Mat12 project_psd(const Mat12& H) { return clamp_eigenvalues<12>(H); }

}  // namespace snh::contact
