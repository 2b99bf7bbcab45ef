// Closed-form and general eigensystems against a brute-force 9x9 eigendecomposition of ∂P/∂F:
// eigenvalues, eigenvectors, and the PSD-projected Hessians (clamp and abs), relative error ≤ 1e-9.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "energies.hpp"

namespace snh {
namespace {

template <class M>
class Eigensystems : public ::testing::Test {};
TYPED_TEST_SUITE(Eigensystems, test::AllEnergies);

/// The σ the issue names: (2,3,5), one negative, all negative, a zero σ, repeated σ, plus random
/// σ in [−1, 1]³.
std::vector<Vec3> sigma_cases() {
  std::vector<Vec3> out = {{2, 3, 5},        {0.4, 0.7, 0.9},  {-0.5, 0.8, 1.2}, {-0.3, -0.6, -0.9},
                           {1.5, 0.0, 0.7},  {0.0, 0.0, 1.0},  {1, 1, 1},        {0.6, 0.6, 0.6},
                           {2, 2, 0.5},      {-0.8, 0.8, 0.8}, {1.1, 1.1, -1.1}, {1, 1, 1e-8}};
  std::mt19937_64 rng(55);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 100; ++i) out.emplace_back(u(rng), u(rng), u(rng));
  return out;
}

/// Brute force: V max(Λ, 0) Vᵀ (or |Λ|) from a 9x9 self-adjoint eigendecomposition.
Mat9 brute_projection(const Mat9& H, PsdProjection p) {
  const Eigen::SelfAdjointEigenSolver<Mat9> es(0.5 * (H + H.transpose()));
  Vec9 d;
  for (int i = 0; i < 9; ++i) d[i] = project_eigenvalue(es.eigenvalues()[i], p);
  return es.eigenvectors() * d.asDiagonal() * es.eigenvectors().transpose();
}

template <class M>
void check_eigensystem(const M& m, const Mat3& F, const std::string& what) {
  const Mat9 H = m.hessian(F);
  const Svd3 svd = rotation_variant_svd(F);
  const Eigensystem9 es = eigensystem(m, svd);
  const double scale = std::max(1.0, H.norm());

  // Eigenvalues, sorted, against brute force.
  Vec9 mine;
  for (int i = 0; i < 9; ++i) mine[i] = es.values[i];
  std::sort(mine.data(), mine.data() + 9);
  const Vec9 brute = Eigen::SelfAdjointEigenSolver<Mat9>(0.5 * (H + H.transpose())).eigenvalues();
  EXPECT_LE((mine - brute).norm() / scale, 1e-9) << M::name << " " << what << "\n" << mine.transpose() << "\n" << brute.transpose();

  // Orthonormal eigenvectors that satisfy H q = λ q.
  EXPECT_LE((es.vectors.transpose() * es.vectors - Mat9::Identity()).norm(), 1e-12) << M::name << " " << what;
  for (int i = 0; i < 9; ++i)
    EXPECT_LE((H * es.vectors.col(i) - es.values[i] * es.vectors.col(i)).norm() / scale, 1e-9)
        << M::name << " " << what << " " << kEigenLabels[i];

  // Projected Hessians, both through the full eigensystem and the fast path.
  for (PsdProjection p : {PsdProjection::none, PsdProjection::clamp, PsdProjection::abs}) {
    const Mat9 reference = brute_projection(H, p);
    const Mat9 fast = projected_hessian(m, F, p);
    const Mat9 full = rebuild(es, p);
    EXPECT_LE((fast - reference).norm() / scale, 1e-9) << M::name << " " << what << " projection " << to_string(p);
    EXPECT_LE((full - reference).norm() / scale, 1e-9) << M::name << " " << what << " projection " << to_string(p);
    if (p != PsdProjection::none) {
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(fast).eigenvalues().minCoeff(), -1e-12 * scale);
    }
  }
}

TYPED_TEST(Eigensystems, AgainstBruteForce) {
  std::mt19937_64 rng(66);
  int checked = 0;
  for (const Lame& p : test::parameter_sets()) {
    const TypeParam m(p);
    for (const Vec3& s : sigma_cases()) {
      if (!TypeParam::inversion_safe && s.prod() <= 0.0) continue;
      if (test::uses_trace_of_S<TypeParam>() && test::min_pair_sum(s) < 0.05) continue;  // singular there
      // Diagonal F (U = V = I) and the same σ under random rotations.
      check_eigensystem(m, Mat3(s.asDiagonal()), "diag sigma=" + std::to_string(s[0]) + "," + std::to_string(s[1]) + "," + std::to_string(s[2]));
      // Under rotation, J of the rounded F has an absolute error ~1e-16, so for the log J energies at
      // J = 1e-8 the Hessian itself (∝ 1/J²) is only defined to ~1e-8 relative: compare on diagonal F only.
      if (TypeParam::inversion_safe || s.prod() > 1e-6)
        check_eigensystem(m, random_matrix_with_sigma(rng, s), "rotated");
      ++checked;
    }
  }
  EXPECT_GE(checked, 30);
}

/// The SNH closed forms equal the general invariant eigensystem of docs/math.md §4.
template <class M>
void closed_form_matches_general(const M& m) {
  for (const Vec3& s : sigma_cases()) {
    const SigmaEigenvalues closed = m.sigma_eigenvalues(s);
    const SigmaEigenvalues general = m.InvariantEnergy<M>::sigma_eigenvalues(s);
    const double scale = std::max(1.0, closed.A.norm());
    EXPECT_LE((closed.twist - general.twist).norm() / scale, 1e-12) << s.transpose();
    EXPECT_LE((closed.flip - general.flip).norm() / scale, 1e-12) << s.transpose();
    EXPECT_LE((closed.A - general.A).norm() / scale, 1e-12) << s.transpose();
  }
}

TEST(ClosedForm, StableNeoHookeanMatchesGeneralInvariantForm) {
  for (const Lame& p : test::parameter_sets()) closed_form_matches_general(StableNeoHookean(p));
}

TEST(ClosedForm, StableNeoHookeanLogMatchesGeneralInvariantForm) {
  for (const Lame& p : test::parameter_sets()) closed_form_matches_general(StableNeoHookeanLog(p));
}

TEST(ClosedForm, MathMdExampleValues) {
  // docs/math.md §4 values at σ = (2, 3, 5), μ = 1, λ = 10, production SNH: J = 30, α = 1.1.
  const StableNeoHookean m({1.0, 10.0});
  const SigmaEigenvalues e = m.sigma_eigenvalues(Vec3(2, 3, 5));
  const double c = 10.0 * (30.0 - 1.1);
  EXPECT_DOUBLE_EQ(e.twist[0], 1.0 + c * 2);
  EXPECT_DOUBLE_EQ(e.flip[2], 1.0 - c * 5);
  EXPECT_DOUBLE_EQ(e.A(0, 0), 1.0 + 10.0 * 9 * 25);
  EXPECT_DOUBLE_EQ(e.A(0, 1), 10.0 * 5 * (60.0 - 1.1));
}

}  // namespace
}  // namespace snh
