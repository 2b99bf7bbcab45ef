// The barrier b(s, ŝ) = −(s − ŝ)² ln(s/ŝ) and its derivatives by finite differences; zero at and beyond ŝ,
// unbounded as s → 0; the PSD projection.
#include <gtest/gtest.h>

#include <random>

#include "fd_check.hpp"
#include "snh/contact/barrier.hpp"
#include "snh/contact/project_psd.hpp"

namespace snh::contact {
namespace {

/// Best relative error over ε (relative steps ε·s) of the central difference of f at s against df.
template <class F>
double fd_error(F&& f, double s, double df) {
  double best = 1e300;
  for (double eps : kFiniteDifferenceSteps) {
    const double h = eps * s;
    const double fd = (-f(s + 2 * h) + 8 * f(s + h) - 8 * f(s - h) + f(s - 2 * h)) / (12 * h);
    best = std::min(best, std::abs(fd - df) / std::max(std::abs(df), 1e-12));
  }
  return best;
}

TEST(Barrier, DerivativesByFiniteDifferences) {
  for (double s_hat : {1e-6, 1e-2, 1.0, 3.0}) {
    const auto b = [s_hat](double s) { return barrier(s, s_hat); };
    const auto db = [s_hat](double s) { return barrier_first_derivative(s, s_hat); };
    for (double frac : {1e-6, 1e-3, 0.1, 0.5, 0.9, 0.999}) {
      const double s = frac * s_hat;
      EXPECT_LE(fd_error(b, s, db(s)), 1e-7) << "b' at s/ŝ = " << frac << ", ŝ = " << s_hat;
      EXPECT_LE(fd_error(db, s, barrier_second_derivative(s, s_hat)), 1e-7) << "b'' at s/ŝ = " << frac;
      EXPECT_GT(b(s), 0.0);
      EXPECT_LT(db(s), 0.0);
      EXPECT_GT(barrier_second_derivative(s, s_hat), 0.0);
    }
  }
}

TEST(Barrier, ZeroAtAndBeyondDhat) {
  for (double s_hat : {1e-4, 1.0}) {
    for (double s : {s_hat, 1.5 * s_hat, 1e10 * s_hat}) {
      EXPECT_EQ(barrier(s, s_hat), 0.0);
      EXPECT_EQ(barrier_first_derivative(s, s_hat), 0.0);
      EXPECT_EQ(barrier_second_derivative(s, s_hat), 0.0);
    }
    // C² at ŝ: the values just below go to 0 with the distance to ŝ.
    const double s = s_hat * (1 - 1e-6);
    EXPECT_LT(barrier(s, s_hat), 1e-17 * s_hat * s_hat);
    EXPECT_LT(std::abs(barrier_first_derivative(s, s_hat)), 1e-11 * s_hat);
    EXPECT_LT(barrier_second_derivative(s, s_hat), 1e-5);
  }
}

TEST(Barrier, UnboundedAsTheDistanceVanishes) {
  const double s_hat = 1e-2;
  double previous = 0.0;
  for (int k = 3; k <= 300; k += 3) {
    const double b = barrier(std::pow(10.0, -k), s_hat);
    EXPECT_GT(b, previous) << "s = 1e-" << k;
    previous = b;
  }
  // b ≈ ŝ² ln(ŝ/s): past any bound as s → 0, and +∞ at contact.
  EXPECT_GT(barrier(1e-300, s_hat), 600 * s_hat * s_hat);
  EXPECT_EQ(barrier(0.0, s_hat), std::numeric_limits<double>::infinity());
  EXPECT_EQ(barrier(-1.0, s_hat), std::numeric_limits<double>::infinity());
  EXPECT_EQ(barrier_first_derivative(0.0, s_hat), -std::numeric_limits<double>::infinity());
}

TEST(ProjectPsd, ClampsNegativeEigenvaluesOnly) {
  std::mt19937_64 rng(22);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 20; ++i) {
    Mat12 A;
    for (int k = 0; k < 144; ++k) A.data()[k] = n(rng);
    const Mat12 H = A + A.transpose();
    const Mat12 P = project_psd(H);
    using Solver = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>;  // (fixed 12×12: a GCC 12 false warning)
    const Solver eh(H), ep(P);
    EXPECT_GE(ep.eigenvalues().minCoeff(), -1e-12 * H.norm());
    // P − H adds exactly the negative part back: PSD, and of rank = the number of negative eigenvalues.
    const Solver ed(Eigen::MatrixXd(P - H));
    EXPECT_GE(ed.eigenvalues().minCoeff(), -1e-12 * H.norm());
    // The eigenvalues (both sorted ascending) are max(λ, 0) of H's.
    EXPECT_NEAR((ep.eigenvalues() - eh.eigenvalues().cwiseMax(0.0)).norm(), 0.0, 1e-10 * H.norm());
    // Already PSD: unchanged.
    const Mat12 S = A * A.transpose();
    EXPECT_LE((project_psd(S) - S).norm(), 1e-12 * S.norm());
  }
}

}  // namespace
}  // namespace snh::contact
