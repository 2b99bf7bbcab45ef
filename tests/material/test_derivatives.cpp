// Finite-difference checks of every energy: P against ψ and ∂P/∂F against P, at random F with J > 0,
// and, where the energy is defined there, at inverted and near-degenerate F. ε is swept and the best
// relative error must be ≤ 1e-6.
#include <gtest/gtest.h>

#include "energies.hpp"
#include <Eigen/Eigenvalues>

#include "snh/material/eigensystem.hpp"
#include "snh/math/finite_difference.hpp"

namespace snh {
namespace {

template <class M>
class Derivatives : public ::testing::Test {};
TYPED_TEST_SUITE(Derivatives, test::AllEnergies);

/// Checks P = ∂ψ/∂F and ∂P/∂F = ∂P/∂F numerically at F; returns false if the sample was skipped.
template <class M>
void check_at(const M& m, const Mat3& F, const char* where) {
  ASSERT_TRUE(m.defined(F));
  const Mat3 P = m.pk1(F);
  const Mat9 H = m.hessian(F);
  ASSERT_TRUE(P.allFinite() && H.allFinite() && std::isfinite(m.psi(F)));
  const double err_P = best_relative_error(
      P, [&](double eps) { return fd_gradient([&](const Mat3& G) { return m.psi(G); }, F, eps); });
  const double err_H = best_relative_error(
      H, [&](double eps) { return fd_jacobian([&](const Mat3& G) { return m.pk1(G); }, F, eps); });
  EXPECT_LE(err_P, 1e-6) << M::name << " P vs FD(psi) " << where << " F=\n" << F;
  EXPECT_LE(err_H, 1e-6) << M::name << " dP/dF vs FD(P) " << where << " F=\n" << F;
}

TYPED_TEST(Derivatives, PositiveJ) {
  std::mt19937_64 rng(101);
  for (const Lame& p : test::parameter_sets()) {
    const TypeParam m(p);
    for (int i = 0; i < 60; ++i) check_at(m, test::sample_F(rng, 0.5, 1.6, i % 2 ? 0 : 2), "J>0");
    // Large and small stretches.
    check_at(m, Vec3(3.5, 0.55, 0.55).asDiagonal(), "stretched 3.5x");
    check_at(m, Vec3(0.3, 0.4, 0.35).asDiagonal(), "compressed");
  }
}

TYPED_TEST(Derivatives, InvertedAndNearDegenerate) {
  if constexpr (!TypeParam::inversion_safe) {
    // No derivatives to check: the energy must say so at every inverted sample.
    std::mt19937_64 rng(202);
    const TypeParam m(test::parameter_sets()[0]);
    for (int i = 0; i < 60; ++i) {
      const Mat3 F = test::sample_F(rng, 0.3, 1.6, 1 + 2 * (i % 2));
      EXPECT_FALSE(m.defined(F));
      EXPECT_EQ(m.psi(F), std::numeric_limits<double>::infinity());
      EXPECT_TRUE(m.pk1(F).isZero() && m.hessian(F).isZero());
    }
  } else {
    std::mt19937_64 rng(202);
    for (const Lame& p : test::parameter_sets()) {
      const TypeParam m(p);
      int checked = 0;
      for (int i = 0; i < 200 && checked < 60; ++i) {
        Vec3 s;
        const int negatives = 1 + (i % 3);  // one, two or three negative singular values
        const Mat3 F = test::sample_F(rng, 0.3, 1.6, negatives, &s);
        if (test::uses_trace_of_S<TypeParam>() && test::min_pair_sum(s) < 0.2) continue;
        check_at(m, F, "inverted");
        ++checked;
      }
      EXPECT_EQ(checked, 60);
      // Near-degenerate: one tiny singular value of either sign, and a nearly flat F.
      for (double tiny : {1e-3, -1e-3, 1e-4}) {
        const Mat3 F = random_matrix_with_sigma(rng, Vec3(1.2, 0.8, tiny));
        check_at(m, F, "near-degenerate");
      }
      if (!test::uses_trace_of_S<TypeParam>()) check_at(m, random_matrix_with_sigma(rng, Vec3(1e-3, 1e-3, 2e-3)), "near zero");
    }
  }
}

TYPED_TEST(Derivatives, SvdFormMatchesFForm) {
  // ψ and P computed from the SVD (what the eigensystem uses) equal the F-space formulas.
  std::mt19937_64 rng(303);
  const TypeParam m(test::parameter_sets()[0]);
  for (int i = 0; i < 100; ++i) {
    Vec3 s;
    const Mat3 F = test::sample_F(rng, 0.3, 1.6, TypeParam::inversion_safe ? i % 4 : 0, &s);
    if (test::uses_trace_of_S<TypeParam>() && test::min_pair_sum(s) < 0.2) continue;
    const Svd3 svd = rotation_variant_svd(F);
    EXPECT_NEAR(psi(m, svd), m.psi(F), 1e-11 * std::max(1.0, std::abs(m.psi(F))));
    EXPECT_LE((pk1(m, svd) - m.pk1(F)).norm(), 1e-11 * std::max(1.0, m.pk1(F).norm()));
  }
}

// The element loop's slices of the Hessian (energies without I1): w·hessian(F)'s entries, bit for bit, at
// upright, inverted and (where undefined: zero) any F, with a weight that is not a power of two.
TYPED_TEST(Derivatives, HessianSlicesAreTheWeightedHessian) {
  if constexpr (!test::uses_trace_of_S<TypeParam>() && requires(const TypeParam& m, const Mat3& F) { m.weighted_hessian_slices(F, 1.0); }) {
    std::mt19937_64 rng(303);
    for (const Lame& p : test::parameter_sets()) {
      const TypeParam m(p);
      for (int i = 0; i < 40; ++i) {
        const Mat3 F = test::sample_F(rng, 0.3, 1.7, i % 4);
        const double w = 0.37 + 0.01 * i;
        const Mat9 H = m.hessian(F) * w;
        const std::array<Mat3, 6> slices = m.weighted_hessian_slices(F, w);
        for (int a = 0; a < 3; ++a)
          for (int k = 0; k <= a; ++k)
            for (int j = 0; j < 3; ++j)
              for (int l = 0; l < 3; ++l)
                ASSERT_EQ(slices[a * (a + 1) / 2 + k](j, l), H(3 * j + a, 3 * l + k))
                    << TypeParam::name << " slice (" << a << ", " << k << ") at (" << j << ", " << l << "), F=\n" << F;
      }
    }
  } else {
    GTEST_SKIP() << "an energy of I1: its Hessian comes from the eigensystem";
  }
}

/// The projected Hessian as the element loop makes it: the analytic slices plus the change the projection makes
/// to the eigenvalues it alters (add_projection_change), against the 9x9 projected Hessian, and the number of
/// eigenvalues changed against a brute-force eigendecomposition of the 9x9 analytic Hessian.
TYPED_TEST(Derivatives, ProjectedSlicesAreTheProjectedHessian) {
  if constexpr (!test::uses_trace_of_S<TypeParam>() && requires(const TypeParam& m, const Mat3& F) { m.weighted_hessian_slices(F, 1.0); }) {
    std::mt19937_64 rng(404);
    int changed_total = 0, unchanged_points = 0;
    for (const Lame& p : test::parameter_sets()) {
      const TypeParam m(p);
      for (int i = 0; i < 60; ++i) {
        const Mat3 F = i % 5 == 4 ? Mat3(Mat3::Identity() * (0.98 + 0.001 * i)) : test::sample_F(rng, 0.3, 1.7, i % 4);
        if (!m.defined(F)) continue;
        const double w = 0.37 + 0.01 * i;
        const Svd3 svd = rotation_variant_svd(F);
        const Eigen::SelfAdjointEigenSolver<Mat9> brute(m.hessian(F));
        int negative = 0;
        for (int e = 0; e < 9; ++e) negative += brute.eigenvalues()[e] < -1e-9 * brute.eigenvalues().cwiseAbs().maxCoeff();
        for (const PsdProjection proj : {PsdProjection::clamp, PsdProjection::abs}) {
          HessianSlices slices = m.weighted_hessian_slices(F, w);
          const int changed = add_projection_change(svd, m.sigma_eigenvalues(svd.sigma), proj, w, slices);
          EXPECT_EQ(changed, negative) << TypeParam::name << " " << to_string(proj) << ", F=\n" << F;
          changed_total += changed;
          unchanged_points += changed == 0;
          const Mat9 H = projected_hessian(m, F, proj) * w;
          const double scale = H.cwiseAbs().maxCoeff();
          for (int a = 0; a < 3; ++a)
            for (int k = 0; k <= a; ++k)
              for (int j = 0; j < 3; ++j)
                for (int l = 0; l < 3; ++l)
                  ASSERT_NEAR(slices[a * (a + 1) / 2 + k](j, l), H(3 * j + a, 3 * l + k), 1e-11 * scale)
                      << TypeParam::name << " " << to_string(proj) << " slice (" << a << ", " << k << ") at (" << j << ", " << l
                      << "), F=\n" << F;
        }
      }
    }
    // Both kinds of point were met: some the projection changes, some it leaves alone.
    EXPECT_GT(changed_total, 0) << TypeParam::name;
    EXPECT_GT(unchanged_points, 0) << TypeParam::name;
  } else {
    GTEST_SKIP() << "an energy of I1: its Hessian comes from the eigensystem";
  }
}

}  // namespace
}  // namespace snh
