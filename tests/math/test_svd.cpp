// Rotation-variant SVD and the 3x3 symmetric eigen-solver: reconstruction, orthogonality,
// determinants, ordering and sign convention on random and hard matrices.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "snh/math/random.hpp"
#include "snh/math/svd.hpp"

namespace snh {
namespace {

/// Checks every property the SVD promises; tol is relative to ‖F‖.
void expect_valid_svd(const Mat3& F, const Svd3& s, double tol = 1e-14) {
  // stableNorm on vec(·): Eigen 3.4.0 asserts in debug builds when it is called on a 3x3 matrix.
  const double scale = std::max(vec(F).stableNorm(), std::numeric_limits<double>::min());
  EXPECT_LE(vec(s.reconstruct() - F).stableNorm() / scale, tol * 10) << "F=\n" << F;
  EXPECT_LE((s.U.transpose() * s.U - Mat3::Identity()).norm(), tol * 10);
  EXPECT_LE((s.V.transpose() * s.V - Mat3::Identity()).norm(), tol * 10);
  EXPECT_NEAR(s.U.determinant(), 1.0, tol * 10);
  EXPECT_NEAR(s.V.determinant(), 1.0, tol * 10);
  EXPECT_GE(s.sigma[0], 0.0);
  EXPECT_GE(s.sigma[1], 0.0);
  EXPECT_GE(s.sigma[0], s.sigma[1]);
  EXPECT_GE(s.sigma[1] + tol * scale, std::abs(s.sigma[2]));
  EXPECT_TRUE(s.U.allFinite() && s.V.allFinite() && s.sigma.allFinite());
}

/// The singular values of F = R1 diag(sigma) R2ᵀ come back, sorted, with the sign of det on the last.
void expect_sigma(const Svd3& s, Vec3 expected, double tol) {
  std::sort(expected.data(), expected.data() + 3, [](double a, double b) { return std::abs(a) > std::abs(b); });
  const bool negative = expected.prod() < 0.0;
  for (int i = 0; i < 3; ++i) expected[i] = std::abs(expected[i]);
  if (negative) expected[2] = -expected[2];
  EXPECT_LE((s.sigma - expected).norm(), tol * std::max(1.0, expected.norm())) << s.sigma.transpose() << " vs "
                                                                             << expected.transpose();
}

TEST(Svd, RandomMatrices) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 20000; ++i) {
    const Mat3 F = random_matrix(rng);
    const Svd3 s = rotation_variant_svd(F);
    expect_valid_svd(F, s);
    if (std::abs(F.determinant()) > 1e-6) {
      EXPECT_EQ(s.sigma[2] < 0.0, F.determinant() < 0.0);
    }
  }
}

TEST(Svd, KnownSingularValuesUnderRandomRotations) {
  std::mt19937_64 rng(11);
  const std::vector<Vec3> cases = {
      {2, 3, 5},       {1, 1, 1},        {2, 2, 1},         {1, 1, 0},      {1, 0, 0},
      {0, 0, 0},       {-1, 1, 1},       {-1, -1, -1},      {0.4, 0.7, -0.9}, {1, 1 + 1e-14, 1},
      {1e8, 1, 1e-8},  {3, -3, 3},       {1e-3, 1e-3, 1e-3}, {5, 0, -2},     {-0.5, 0.8, 1.2}};
  for (const Vec3& sigma : cases) {
    for (int rep = 0; rep < 50; ++rep) {
      const Mat3 F = random_matrix_with_sigma(rng, sigma);
      const Svd3 s = rotation_variant_svd(F);
      expect_valid_svd(F, s);
      expect_sigma(s, sigma, 1e-13);
    }
  }
}

TEST(Svd, ExactSpecialMatrices) {
  // Zero, identity, reflections, rank 1 and rank 2, exact diagonal.
  std::vector<Mat3> cases;
  cases.push_back(Mat3::Zero());
  cases.push_back(Mat3::Identity());
  cases.push_back(-Mat3::Identity());
  cases.push_back(Vec3(1, 1, -1).asDiagonal());
  cases.push_back(Vec3(-2, 3, 0.5).asDiagonal());
  cases.push_back(Vec3(1, 2, 3).asDiagonal());
  cases.push_back(Vec3(1, 2, 3) * Vec3(-1, 0.5, 2).transpose());  // rank 1
  Mat3 rank2;
  rank2 << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  cases.push_back(rank2);
  Mat3 column_zero = Mat3::Random();
  column_zero.col(1).setZero();
  cases.push_back(column_zero);
  Mat3 single = Mat3::Zero();
  single(2, 0) = -4.0;
  cases.push_back(single);
  for (const Mat3& F : cases) expect_valid_svd(F, rotation_variant_svd(F));
  // Exact values on diagonal inputs.
  expect_sigma(rotation_variant_svd(Vec3(-2, 3, 0.5).asDiagonal()), Vec3(-2, 3, 0.5), 1e-15);
  expect_sigma(rotation_variant_svd(-Mat3::Identity()), Vec3(-1, -1, -1), 1e-15);
  const Svd3 r2 = rotation_variant_svd(rank2);
  EXPECT_LE(std::abs(r2.sigma[2]), 1e-14 * rank2.norm());
}

TEST(Svd, TinyAndHugeScales) {
  std::mt19937_64 rng(3);
  for (double scale : {1e-300, 1e-200, 1e-20, 1e20, 1e200, 1e300}) {
    for (int rep = 0; rep < 100; ++rep) {
      const Mat3 F = random_matrix(rng) * scale;
      const Svd3 s = rotation_variant_svd(F);
      expect_valid_svd(F, s);
    }
  }
  // Denormal entries.
  Mat3 F = Mat3::Zero();
  F(0, 1) = 4e-320;
  F(2, 2) = -1e-319;
  expect_valid_svd(F, rotation_variant_svd(F), 1e-3);
}

TEST(Svd, ExtremeScalesAndRatiosKeepTheSignOfDet) {
  // Issue 13: diag(1e150, 1, 1) came back as sigma = (1e150, 1, -1): the completion of U treated the
  // scaled sigma_1 = 5e-151 as zero. One stretched axis (ratio up to 1e150), a uniform scale
  // (1e-150..1e150), with and without a reflection, on the diagonal and under random rotations.
  std::mt19937_64 rng(13);
  for (int e = -150; e <= 150; e += 10) {
    const double s = std::pow(10.0, e);
    for (const Vec3& sigma : {Vec3(s, 1, 1), Vec3(s, 1, -1), Vec3(-s, 1, 1), Vec3(1, s, 1), Vec3(1, 1, -s),
                              Vec3(s, s, s), Vec3(s, -s, s), Vec3(-s, -s, -s), Vec3(s, 2 * s, -3 * s)}) {
      const bool negative = (sigma.array() < 0.0).count() % 2 == 1;  // the product would underflow
      const Svd3 d = rotation_variant_svd(Mat3(sigma.asDiagonal()));
      EXPECT_EQ(d.sigma[2] < 0.0, negative) << "diag " << sigma.transpose() << " -> " << d.sigma.transpose();
      expect_sigma(d, sigma, 1e-15);
      expect_valid_svd(Mat3(sigma.asDiagonal()), d);
      for (int rep = 0; rep < 5; ++rep) {
        const Mat3 F = random_matrix_with_sigma(rng, sigma);
        const Svd3 r = rotation_variant_svd(F);
        expect_valid_svd(F, r);
        // Rotated, the entries of F keep the small singular values only while the ratio stays well
        // under 1/eps; past that even the sign of det F is rounding, so it is checked up to 1e6.
        const double ratio = sigma.cwiseAbs().maxCoeff() / sigma.cwiseAbs().minCoeff();
        if (ratio <= 1e6) {
          EXPECT_EQ(r.sigma[2] < 0.0, negative) << sigma.transpose() << " -> " << r.sigma.transpose();
        }
      }
    }
  }
}

TEST(Svd, NonFiniteInputGivesNaNSigmaNotGarbage) {
  for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    Mat3 F = Mat3::Identity();
    F(1, 2) = bad;
    const Svd3 s = rotation_variant_svd(F);
    EXPECT_TRUE(s.sigma.array().isNaN().all());
    EXPECT_TRUE(s.U.isIdentity() && s.V.isIdentity());
  }
}

TEST(Svd, MoveReflectionKeepsTheDecomposition) {
  std::mt19937_64 rng(5);
  for (int rep = 0; rep < 200; ++rep) {
    Mat3 F = random_matrix(rng);
    if (F.determinant() > 0) F.col(0) = -F.col(0);
    const Svd3 base = rotation_variant_svd(F);
    ASSERT_LT(base.sigma[2], 0.0);
    for (int k = 0; k < 3; ++k) {
      const Svd3 moved = move_reflection(base, k);
      EXPECT_LE((moved.reconstruct() - F).norm(), 1e-13 * F.norm());
      EXPECT_NEAR(moved.U.determinant(), 1.0, 1e-13);
      EXPECT_LT(moved.sigma[k], 0.0);
      for (int i = 0; i < 3; ++i)
        if (i != k) {
          EXPECT_GE(moved.sigma[i], 0.0);
        }
      EXPECT_NEAR(moved.sigma.prod(), base.sigma.prod(), 1e-13);
    }
  }
}

TEST(SymmetricEigen3, AgainstEigenSolver) {
  std::mt19937_64 rng(9);
  std::vector<Mat3> cases;
  for (int i = 0; i < 2000; ++i) {
    const Mat3 R = random_matrix(rng, -3, 3);
    cases.push_back(R + R.transpose());
  }
  cases.push_back(Mat3::Identity());
  cases.push_back(Mat3::Zero());
  cases.push_back(Mat3::Ones());                                   // eigenvalues 3, 0, 0
  cases.push_back(random_rotation(rng) * Vec3(2, 2, -1).asDiagonal() * Mat3::Identity());
  const Mat3 Q = random_rotation(rng);
  cases.push_back(Q * Vec3(1e-12, 1, 1).asDiagonal() * Q.transpose());
  for (Mat3 A : cases) {
    A = 0.5 * (A + A.transpose()).eval();
    const SymEigen3 e = symmetric_eigen3(A);
    const double scale = std::max(A.norm(), 1e-300);
    EXPECT_LE((A * e.vectors - e.vectors * e.values.asDiagonal()).norm() / scale, 1e-14);
    EXPECT_LE((e.vectors.transpose() * e.vectors - Mat3::Identity()).norm(), 1e-14);
    Vec3 got = e.values;
    std::sort(got.data(), got.data() + 3);
    const Vec3 ref = Eigen::SelfAdjointEigenSolver<Mat3>(A).eigenvalues();  // ascending
    EXPECT_LE((got - ref).norm() / scale, 1e-14);
  }
}

}  // namespace
}  // namespace snh
