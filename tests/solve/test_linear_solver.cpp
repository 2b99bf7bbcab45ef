// Linear solvers: the three agree on a positive definite system; try_factorize and PCG recognise an
// indefinite matrix; the shifted factorization still solves a nearly singular one.
#include <gtest/gtest.h>

#include <random>

#include "snh/solve/linear_solver.hpp"

namespace snh {
namespace {

/// Lower triangle of a random sparse SPD (diagonally dominant) matrix, with `shift` added to the diagonal.
SparseLower random_matrix(int n, double shift, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> t;
  Eigen::VectorXd rowsum = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n; ++i)
    for (int j : {i - 1, i - 7}) {
      if (j < 0) continue;
      const double v = u(rng);
      t.emplace_back(i, j, v);
      rowsum[i] += std::abs(v);
      rowsum[j] += std::abs(v);
    }
  for (int i = 0; i < n; ++i) t.emplace_back(i, i, rowsum[i] + 0.5 + shift);
  SparseLower A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  A.makeCompressed();
  return A;
}

TEST(LinearSolver, AllKindsAgreeOnAPositiveDefiniteSystem) {
  const SparseLower A = random_matrix(200, 0.0, 1);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(200, -1.0, 2.0);
  for (LinearSolverKind k : {LinearSolverKind::cholmod, LinearSolverKind::ldlt, LinearSolverKind::pcg}) {
    auto s = make_linear_solver(k);
    ASSERT_TRUE(s->try_factorize(A)) << to_string(k);
    const Eigen::VectorXd x = s->solve(b);
    const Eigen::VectorXd r = Eigen::MatrixXd(A).selfadjointView<Eigen::Lower>() * x - b;
    EXPECT_LE(r.norm(), 1e-9 * b.norm()) << to_string(k);
    if (k == LinearSolverKind::pcg) EXPECT_GT(s->last_iterations(), 0);
    EXPECT_EQ(s->factorize(A), 0.0) << "no shift needed";
  }
}

TEST(LinearSolver, IndefiniteMatricesAreRecognised) {
  const SparseLower A = random_matrix(100, -10.0, 2);  // diagonal pushed far negative: indefinite
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(100);
  for (LinearSolverKind k : {LinearSolverKind::cholmod, LinearSolverKind::ldlt}) {
    auto s = make_linear_solver(k);
    EXPECT_FALSE(s->try_factorize(A)) << to_string(k);
    // factorize() shifts the diagonal until the matrix is positive definite.
    EXPECT_GT(s->factorize(A), 0.0) << to_string(k);
    EXPECT_TRUE(s->solve(b).allFinite());
  }
  auto pcg = make_linear_solver(LinearSolverKind::pcg);
  ASSERT_TRUE(pcg->try_factorize(A));
  EXPECT_FALSE(pcg->solve(b).allFinite()) << "PCG must report non-positive curvature";
}

TEST(LinearSolver, Names) {
  EXPECT_EQ(parse_linear_solver("cholmod"), LinearSolverKind::cholmod);
  EXPECT_EQ(parse_linear_solver("pcg"), LinearSolverKind::pcg);
  EXPECT_FALSE(parse_linear_solver("umfpack").has_value());
}

}  // namespace
}  // namespace snh
