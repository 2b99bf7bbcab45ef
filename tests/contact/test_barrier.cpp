// The barrier b(s, ŝ) = −(s − ŝ)² ln(s/ŝ) and its derivatives by finite differences; zero at and beyond ŝ,
// unbounded as s → 0; the barrier of a pair's squared distance by the chain rule; the PSD projection.
#include <gtest/gtest.h>

#include <random>

#include "fd_check.hpp"
#include "snh/contact/barrier.hpp"
#include "snh/contact/point_triangle_distance.hpp"
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

/// The barrier of a point–triangle pair through the chain rule (what a contact term computes per pair):
/// ∇(b∘s) = b'∇s, ∇²(b∘s) = b''∇s∇sᵀ + b'∇²s, checked by finite differences.
TEST(Barrier, ChainRuleThroughAPairDistance) {
  std::mt19937_64 rng(21);
  const double dhat = 0.5, s_hat = dhat * dhat;
  int active = 0;
  for (int i = 0; i < 200 && active < 40; ++i) {
    const std::array<Vec3, 4> x = {test::random_point(rng, -0.6, 0.6), test::random_point(rng),
                                   test::random_point(rng), test::random_point(rng)};
    const auto type = point_triangle_distance_type(x[0], x[1], x[2], x[3]);
    if (point_triangle_distance(x[0], x[1], x[2], x[3]) >= s_hat) continue;
    ++active;
    const auto energy = [&](const std::array<Vec3, 4>& y) {
      const auto s = point_triangle_distance_derivatives(y[0], y[1], y[2], y[3], type);
      Derivatives<12> e;
      const double b1 = barrier_first_derivative(s.value, s_hat);
      e.value = barrier(s.value, s_hat);
      e.gradient = b1 * s.gradient;
      e.hessian = barrier_second_derivative(s.value, s_hat) * s.gradient * s.gradient.transpose() + b1 * s.hessian;
      return e;
    };
    test::expect_derivatives(energy, x, "barrier of point-triangle " + std::string(to_string(type)), 1e-6, 1e-8);
  }
  EXPECT_GE(active, 40);
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
