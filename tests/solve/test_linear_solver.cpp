// Linear solvers: the three agree on a positive definite system; try_factorize and PCG recognise an
// indefinite matrix; the shifted factorization still solves a nearly singular one.
#include <gtest/gtest.h>

#include <random>

#include <dlfcn.h>

#include "snh/mesh/box.hpp"
#include "snh/solve/direct_solver.hpp"
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
  for (const char* k : {"cholmod", "ldlt", "pcg"}) {
    auto s = make_linear_solver({.name = k});
    ASSERT_TRUE(s->try_factorize(A)) << k;
    const Eigen::VectorXd x = s->solve(b);
    const Eigen::VectorXd r = Eigen::MatrixXd(A).selfadjointView<Eigen::Lower>() * x - b;
    EXPECT_LE(r.norm(), 1e-9 * b.norm()) << k;
    if (std::string(k) == "pcg") {
      EXPECT_GT(s->last_iterations(), 0);
    }
    EXPECT_EQ(s->factorize(A), 0.0) << "no shift needed";
  }
}

TEST(DirectSolver, SmallFactorizationsRunTheBlasOnOneThread) {
  using Get = int (*)();
  const auto threads = reinterpret_cast<Get>(::dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  const int own = choose_blas_threads(1e12);  // a large factorization: OpenBLAS's own count
  if (own == 0 || !threads) GTEST_SKIP() << "the BLAS is not OpenBLAS";
  EXPECT_EQ(threads(), own);
  EXPECT_EQ(choose_blas_threads(1e6), 1);
  EXPECT_EQ(choose_blas_threads(1e12), own) << "a larger factorization gets the threads back";
  // CHOLMOD's analysis of a small matrix chooses one thread by itself.
  auto s = make_linear_solver({.name = "cholmod"});
  ASSERT_TRUE(s->try_factorize(random_matrix(300, 0.0, 3)));
  EXPECT_EQ(threads(), 1);
  (void)choose_blas_threads(1e12);
}

TEST(LinearSolver, IndefiniteMatricesAreRecognised) {
  const SparseLower A = random_matrix(100, -10.0, 2);  // diagonal pushed far negative: indefinite
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(100);
  for (const char* k : {"cholmod", "ldlt"}) {
    auto s = make_linear_solver({.name = k});
    EXPECT_FALSE(s->try_factorize(A)) << k;
    // factorize() shifts the diagonal until the matrix is positive definite.
    EXPECT_GT(s->factorize(A), 0.0) << k;
    EXPECT_TRUE(s->solve(b).allFinite());
  }
  auto pcg = make_linear_solver({.name = "pcg"});
  ASSERT_TRUE(pcg->try_factorize(A));
  EXPECT_FALSE(pcg->solve(b).allFinite()) << "PCG must report non-positive curvature";
}

double residual(const SparseLower& A, const Eigen::VectorXd& x, const Eigen::VectorXd& b) {
  return (Eigen::MatrixXd(A).selfadjointView<Eigen::Lower>() * x - b).norm();
}

/// A with every entry scaled by (1 + eps·u), u uniform in [−1, 1]: a nearby matrix of the same pattern.
SparseLower perturbed(SparseLower A, double eps, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Eigen::Index i = 0; i < A.nonZeros(); ++i) A.valuePtr()[i] *= 1.0 + eps * u(rng);
  return A;
}

TEST(FactorReuse, ANearbyMatrixIsSolvedWithTheOldFactorAsPreconditioner) {
  const SparseLower A = random_matrix(300, 0.0, 3), B = perturbed(A, 0.05, 4);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(300, 1.0, -2.0);
  for (const char* k : {"cholmod", "ldlt"}) {
    auto s = make_linear_solver({.name = k});
    ASSERT_TRUE(s->try_factorize(A));
    EXPECT_LE(residual(A, s->solve(b), b), 1e-12 * b.norm());
    EXPECT_EQ(s->last_iterations(), 0) << "the first matrix is solved directly";
    ASSERT_TRUE(s->try_factorize(B));
    const Eigen::VectorXd x = s->solve(b);
    EXPECT_LE(residual(B, x, b), 1e-10 * b.norm()) << k;
    EXPECT_GT(s->last_iterations(), 1) << "conjugate gradients on the new matrix";
    EXPECT_LE(s->last_iterations(), 10) << "a 5% change: the old factor is a good preconditioner";
    EXPECT_EQ(s->factorizations(), 1) << k;
    // An absolute `enough` lets the iteration stop earlier, at that residual.
    const int full = s->last_iterations();
    ASSERT_TRUE(s->try_factorize(B));
    const Eigen::VectorXd rough = s->solve(b, 1e-3 * b.norm());
    EXPECT_LE(residual(B, rough, b), 1e-3 * b.norm());
    EXPECT_LT(s->last_iterations(), full);
  }
}

TEST(FactorReuse, AFarAwayMatrixIsFactorizedAfresh) {
  const SparseLower A = random_matrix(300, 0.0, 5), B = random_matrix(300, 0.0, 6);  // same pattern, other values
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(300);
  auto s = make_linear_solver({.name = "cholmod", .reuse_iterations = 3});
  ASSERT_TRUE(s->try_factorize(A));
  (void)s->solve(b);
  ASSERT_TRUE(s->try_factorize(B));
  const Eigen::VectorXd x = s->solve(b);
  EXPECT_LE(residual(B, x, b), 1e-12 * b.norm());
  EXPECT_EQ(s->last_iterations(), 3) << "gave up on the old factor after reuse_iterations";
  EXPECT_EQ(s->factorizations(), 2);
  // The new factor is exact for B: reused, it converges at once.
  ASSERT_TRUE(s->try_factorize(B));
  EXPECT_LE(residual(B, s->solve(b), b), 1e-10 * b.norm());
  EXPECT_EQ(s->last_iterations(), 1);
  EXPECT_EQ(s->factorizations(), 2);
}

TEST(FactorReuse, AnIndefiniteMatrixIsStillRecognisedAndShiftedWhenRequired) {
  const SparseLower A = random_matrix(100, 0.0, 7), C = random_matrix(100, -10.0, 7);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(100);
  for (const char* k : {"cholmod", "ldlt"}) {
    auto s = make_linear_solver({.name = k});
    ASSERT_TRUE(s->try_factorize(A));
    (void)s->solve(b);
    // With a factor held, try_factorize accepts C; the solve finds non-positive curvature.
    ASSERT_TRUE(s->try_factorize(C));
    EXPECT_FALSE(s->solve(b).allFinite()) << k;
    EXPECT_EQ(s->factorizations(), 1);
    // factorize() must deliver: the reuse fails, so C is factorized with a shift.
    (void)s->factorize(C);
    EXPECT_TRUE(s->solve(b).allFinite()) << k;
    EXPECT_GT(s->factorizations(), 2) << "at least one failed and one shifted factorization";
  }
}

TEST(FactorReuse, CanBeTurnedOff) {
  const SparseLower A = random_matrix(100, 0.0, 8), B = perturbed(A, 0.05, 9);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(100);
  auto s = make_linear_solver({.name = "cholmod", .reuse_factor = false});
  for (const SparseLower* M : {&A, &B}) {
    ASSERT_TRUE(s->try_factorize(*M));
    EXPECT_LE(residual(*M, s->solve(b), b), 1e-12 * b.norm());
    EXPECT_EQ(s->last_iterations(), 0);
  }
  EXPECT_EQ(s->factorizations(), 2);
}

TEST(LinearSolver, Registry) {
  EXPECT_EQ(linear_solver_names(), (std::vector<std::string>{"cholmod", "ldlt", "pcg", "mg", "amg", "auto"}));
  EXPECT_TRUE(is_linear_solver("pcg"));
  EXPECT_FALSE(is_linear_solver("umfpack"));
  for (const auto& info : linear_solvers()) {
    if (info.name != "mg" && info.name != "amg" && info.name != "auto") {
      EXPECT_EQ(make_linear_solver({.name = std::string(info.name)})->name(), info.name);
    }
  }
  // "mg" and "amg" need the mesh behind the matrix (test_multigrid).
  try {
    (void)make_linear_solver({.name = "umfpack"});
    FAIL() << "an unknown name must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown linear solver 'umfpack' (known: cholmod, ldlt, pcg, mg, amg, auto)");
  }
}

// "auto" chooses by the free DOFs and the mesh: the direct solver below kAutoIterativeFrom, then mg on a hex
// lattice and amg on tets (or hexes that are no lattice); a matrix with no mesh behind it gets the direct one.
TEST(LinearSolver, AutoChoosesBySizeAndMesh) {
  EXPECT_EQ(auto_linear_solver(kAutoIterativeFrom - 1, true), "cholmod");
  EXPECT_EQ(auto_linear_solver(kAutoIterativeFrom, true), "mg");
  EXPECT_EQ(auto_linear_solver(kAutoIterativeFrom, false), "amg");
  EXPECT_EQ(make_linear_solver({.name = "auto"})->name(), "cholmod");
  auto chosen = [](const VolumeMesh& mesh) {
    const std::vector<int> free_index = [&] {
      std::vector<int> f(3 * static_cast<std::size_t>(mesh.vertex_count()));
      for (std::size_t d = 0; d < f.size(); ++d) f[d] = static_cast<int>(d);
      return f;
    }();
    return std::string(make_linear_solver({.name = "auto"}, {.mesh = &mesh, .free_index = &free_index})->name());
  };
  // 3 (r+1)³ free DOFs: r = 10 has 3 993, r = 19 has 24 000.
  EXPECT_EQ(chosen(box_hexes(10)), "cholmod");
  EXPECT_EQ(chosen(box_hexes(19)), "mg");
  EXPECT_EQ(chosen(box_tets(19)), "amg");
  // Hexes that do not fit together as a lattice (one cell's corners relabelled by a quarter turn about z:
  // its x axis along the others' y): amg.
  VolumeMesh turned = box_hexes(19);
  const Eigen::VectorXi old = turned.cells.col(0);
  for (int a = 0; a < 8; a += 4) {
    turned.cells(a, 0) = old[a + 1];
    turned.cells(a + 1, 0) = old[a + 3];
    turned.cells(a + 2, 0) = old[a];
    turned.cells(a + 3, 0) = old[a + 2];
  }
  EXPECT_EQ(chosen(turned), "amg");
}

/// A preconditioner that counts its applications, around Jacobi.
class Counting final : public Preconditioner {
 public:
  explicit Counting(const SparseLower& A) : jacobi_(A) {}
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override {
    ++calls;
    jacobi_.apply(r, z);
  }
  mutable int calls = 0;

 private:
  JacobiPreconditioner jacobi_;
};

TEST(ConjugateGradients, TakesAnyPreconditionerAndReportsHowItStopped) {
  const SparseLower A = random_matrix(150, 0.0, 10), C = random_matrix(150, -10.0, 10);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(150, -1.0, 1.0);
  Counting M(A);
  Eigen::VectorXd x;
  const CgResult r = conjugate_gradients(A, b, M, 1e-10 * b.norm(), 1000, x);
  EXPECT_EQ(r.status, CgStatus::converged);
  EXPECT_LE(residual(A, x, b), 1e-10 * b.norm());
  EXPECT_EQ(M.calls, r.iterations + 1) << "one application per iteration and one at the start";
  EXPECT_NEAR(r.residual, residual(A, x, b), 1e-12 * b.norm()) << "the residual reported is the returned x's";
  const CgResult two = conjugate_gradients(A, b, M, 1e-14 * b.norm(), 2, x);
  EXPECT_EQ(two.status, CgStatus::exhausted);
  EXPECT_NEAR(two.residual, residual(A, x, b), 1e-12 * b.norm());
  EXPECT_GT(two.residual, 1e-3 * b.norm());
  const CgResult bad = conjugate_gradients(C, b, JacobiPreconditioner(C), 1e-10, 1000, x);
  EXPECT_EQ(bad.status, CgStatus::indefinite);
  EXPECT_NEAR(bad.residual, residual(C, x, b), 1e-9 * b.norm()) << "the iterate before the non-positive curvature";
}

}  // namespace
}  // namespace snh
