// Fibre energies and active strain (material/fibre.hpp): P against finite differences of ψ and ∂P/∂F against
// finite differences of P, at random F with J > 0, inverted and near-degenerate; the closed-form eigensystem
// against a brute-force eigendecomposition of ∂P/∂F (values, H v = λ v, orthonormal vectors); the projection;
// the signed model telling a fibre reversed by inversion from a stretched one; and active strain: det F_a = 1,
// its derivatives through the congruence, and a free element that settles exactly at F = R F_a.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "energies.hpp"
#include "snh/material/fibre.hpp"
#include "snh/material/stable_neo_hookean.hpp"
#include "snh/math/finite_difference.hpp"
#include "snh/math/random.hpp"

namespace snh {
namespace {

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vec3(n(rng), n(rng), n(rng)).normalized();
}

/// aᵀ S a for F = R S (S from the rotation-variant SVD).
double fibre_stretch_sign_value(const Mat3& F, const Vec3& a) {
  const Svd3 svd = rotation_variant_svd(F);
  return a.dot(svd.V * svd.sigma.asDiagonal() * svd.V.transpose() * a);
}

void check_derivatives(const FibreEnergy& e, const Mat3& F, const Vec3& a, const char* where) {
  const Mat3 P = e.pk1(F, a);
  const Mat9 H = e.hessian(F, a);
  ASSERT_TRUE(P.allFinite() && H.allFinite() && std::isfinite(e.psi(F, a)));
  const double err_P = best_relative_error(P, [&](double eps) { return fd_gradient([&](const Mat3& G) { return e.psi(G, a); }, F, eps); });
  const double err_H = best_relative_error(H, [&](double eps) { return fd_jacobian([&](const Mat3& G) { return e.pk1(G, a); }, F, eps); });
  EXPECT_LE(err_P, 1e-6) << to_string(e.model) << " P vs FD(psi) " << where << " F=\n" << F;
  EXPECT_LE(err_H, 1e-6) << to_string(e.model) << " dP/dF vs FD(P) " << where << " F=\n" << F;
}

void check_eigensystem(const FibreEnergy& e, const Mat3& F, const Vec3& a, const char* where) {
  const Mat9 H = e.hessian(F, a);
  const Eigensystem9 es = e.eigensystem(F, a);
  const double scale = std::max(1.0, H.norm());
  // The vectors are orthonormal and each is an eigenvector with its value.
  EXPECT_LE((es.vectors.transpose() * es.vectors - Mat9::Identity()).norm(), 1e-12) << where;
  for (int i = 0; i < 9; ++i)
    EXPECT_LE((H * es.vectors.col(i) - es.values[i] * es.vectors.col(i)).norm(), 1e-10 * scale) << where << " vector " << i;
  // The values are those of a brute-force eigendecomposition.
  std::array<double, 9> closed = es.values;
  std::sort(closed.begin(), closed.end());
  const Vec9 brute = Eigen::SelfAdjointEigenSolver<Mat9>(H).eigenvalues();
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(closed[static_cast<std::size_t>(i)], brute[i], 1e-10 * scale) << where << " value " << i;
  // The projection: PSD, and the Hessian itself where nothing is negative.
  const Mat9 Hp = e.projected_hessian(F, a, PsdProjection::clamp);
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(Hp).eigenvalues().minCoeff(), -1e-10 * scale) << where;
  if (*std::min_element(es.values.begin(), es.values.end()) >= 0.0) {
    EXPECT_LE((Hp - H).norm(), 1e-10 * scale) << where;
  }
}

TEST(Fibre, DerivativesAndEigensystemsAtPositiveInvertedAndDegenerateF) {
  std::mt19937_64 rng(4242);
  for (const FibreModel model : {FibreModel::quadratic, FibreModel::signed_arap}) {
    const FibreEnergy e{model, 3.5};
    int checked = 0, inverted = 0, negative = 0;
    for (int i = 0; i < 400 && checked < 90; ++i) {
      const int negatives = i % 3 == 0 ? 0 : i % 3 == 1 ? 1 : 3;
      Mat3 F = test::sample_F(rng, 0.2, 2.2, negatives);
      if (i % 10 == 9) F.col(2) = 0.3 * F.col(0) - 0.7 * F.col(1);  // rank 2: a degenerate element
      Vec3 a = random_unit(rng);
      if (i % 4 == 1) {  // a fibre near the reversed singular direction of an inverted F: aᵀ S a < 0 mostly
        const Svd3 svd = rotation_variant_svd(F);
        a = (svd.V.col(2) + 0.3 * a).normalized();
      }
      // The signed model's ψ jumps where aᵀ S a changes sign, and its f′ is unbounded as F a → 0: keep the
      // finite-difference stencils (up to 2 · 1e-2 per entry) away from both.
      if (model == FibreModel::signed_arap && (std::abs(fibre_stretch_sign_value(F, a)) < 0.2 || (F * a).norm() < 0.2)) continue;
      ++checked;
      inverted += F.determinant() < 0.0;
      negative += fibre_sign(F, a) < 0.0;
      check_derivatives(e, F, a, F.determinant() < 0.0 ? "inverted" : "J>=0");
      check_eigensystem(e, F, a, F.determinant() < 0.0 ? "inverted" : "J>=0");
    }
    EXPECT_EQ(checked, 90) << to_string(model);
    EXPECT_GT(inverted, 20) << to_string(model);
    EXPECT_GE(negative, 10) << to_string(model) << ": fibres reversed by inversion, checked";
  }
}

TEST(Fibre, TheEigenvaluesAreThoseOfTheClosedForm) {
  // Along the fibre λ = 2f′ + 4 I4 f″, across it 2f′ twice: for the signed model k and k(1 − σ/√I4).
  const double k = 2.0;
  const Vec3 a = Vec3(1, 2, 2) / 3.0;
  const Mat3 F = Vec3(1.5, 0.8, 1.1).asDiagonal();
  const double r = (F * a).norm();
  const Eigensystem9 s = FibreEnergy{FibreModel::signed_arap, k}.eigensystem(F, a);
  EXPECT_DOUBLE_EQ(s.values[0], k);
  EXPECT_NEAR(s.values[1], k * (1.0 - 1.0 / r), 1e-14);
  const Eigensystem9 q = FibreEnergy{FibreModel::quadratic, k}.eigensystem(F, a);
  EXPECT_NEAR(q.values[0], 0.5 * k * (3.0 * r * r - 1.0), 1e-14);
  EXPECT_NEAR(q.values[2], 0.5 * k * (r * r - 1.0), 1e-14);
  for (int i = 3; i < 9; ++i) EXPECT_EQ(s.values[static_cast<std::size_t>(i)], 0.0);
}

TEST(Fibre, TheSignedModelTellsAReversedFibreFromAStretchedOne) {
  // An element turned inside out along the fibre: F a = −a. The quadratic model sees a fibre at rest length
  // (ψ = 0, no force); the signed model sees it compressed through zero (s = −1, ψ = 2k) and pushes back.
  const Vec3 a = Vec3::UnitX();
  const Mat3 F = Vec3(-1.0, 1.0, 1.0).asDiagonal();
  const FibreEnergy quadratic{FibreModel::quadratic, 1.0}, signed_arap{FibreModel::signed_arap, 1.0};
  EXPECT_EQ(fibre_sign(F, a), -1.0);
  EXPECT_EQ(quadratic.psi(F, a), 0.0);
  EXPECT_TRUE(quadratic.pk1(F, a).isZero());
  EXPECT_DOUBLE_EQ(signed_arap.psi(F, a), 2.0);
  // P = k(1 − σ/√I4) F a aᵀ = 2 (−a) aᵀ: along −∂ψ/∂F the fibre grows back through zero towards +a.
  EXPECT_LE((signed_arap.pk1(F, a) - Mat3(-2.0 * a * a.transpose())).norm(), 1e-15);
  // At rest both are zero, and stretched both positive.
  EXPECT_EQ(signed_arap.psi(Mat3::Identity(), a), 0.0);
  EXPECT_GT(signed_arap.psi(Vec3(1.3, 1, 1).asDiagonal(), a), 0.0);
  // A collapsed fibre (F a = 0): finite ψ, P = 0, and the eigensystem's fallback.
  const Mat3 flat = Vec3(0.0, 1.0, 1.0).asDiagonal();
  EXPECT_DOUBLE_EQ(signed_arap.psi(flat, a), 0.5);
  EXPECT_TRUE(signed_arap.pk1(flat, a).isZero());
  EXPECT_TRUE(signed_arap.hessian(flat, a).allFinite());
}

TEST(ActiveStrain, ShortensTheFibreAndKeepsTheVolume) {
  std::mt19937_64 rng(77);
  for (const double alpha : {0.0, 0.1, 0.35, 0.8}) {
    const Vec3 a = random_unit(rng);
    const ActiveStrain s = ActiveStrain::along(3.0 * a, alpha);  // normalised
    const Mat3 Fa = s.deformation();
    EXPECT_NEAR(Fa.determinant(), 1.0, 1e-13);
    EXPECT_LE((Fa * a - (1.0 - alpha) * a).norm(), 1e-13);
    Vec3 b, c;
    b = a.unitOrthogonal();
    c = a.cross(b);
    EXPECT_LE((Fa * b - b / std::sqrt(1.0 - alpha)).norm(), 1e-13);
    EXPECT_LE((Fa * c - c / std::sqrt(1.0 - alpha)).norm(), 1e-13);
    EXPECT_LE((Fa - Fa.transpose()).norm(), 1e-14);
  }
  EXPECT_THROW((void)ActiveStrain::along(Vec3::Zero(), 0.1), std::invalid_argument);
  EXPECT_THROW((void)ActiveStrain::along(Vec3::UnitX(), 1.0), std::invalid_argument);
  EXPECT_THROW((void)ActiveStrain::along(Vec3::UnitX(), -0.1), std::invalid_argument);
  EXPECT_THROW((void)ActiveStrain::along(Vec3::UnitX(), std::nan("")), std::invalid_argument);
}

/// A muscle's energy at one F: Stable Neo-Hookean plus a fibre, on the elastic part F A.
struct Muscle {
  StableNeoHookean base{Lame{1.0, 10.0}};
  FibreEnergy fibre{FibreModel::signed_arap, 4.0};
  Vec3 a;
  ActiveStrain active;
  [[nodiscard]] double psi(const Mat3& F) const {
    const Mat3 E = active.elastic(F);
    return base.psi(E) + fibre.psi(E, a);
  }
  [[nodiscard]] Mat3 pk1(const Mat3& F) const {
    const Mat3 E = active.elastic(F);
    return active.pk1(base.pk1(E) + fibre.pk1(E, a));
  }
  [[nodiscard]] Mat9 hessian(const Mat3& F, PsdProjection p = PsdProjection::none) const {
    const Mat3 E = active.elastic(F);
    return active.hessian(projected_hessian(base, E, p) + fibre.projected_hessian(E, a, p));
  }
};

TEST(ActiveStrain, DerivativesThroughTheCongruenceMatchFiniteDifferences) {
  std::mt19937_64 rng(78);
  for (int i = 0; i < 30; ++i) {
    Muscle m;
    m.a = random_unit(rng);
    m.active = ActiveStrain::along(m.a, 0.05 * (i % 10));
    const Mat3 F = test::sample_F(rng, 0.6, 1.5, 0);
    if (std::abs(fibre_stretch_sign_value(m.active.elastic(F), m.a)) < 0.2) continue;
    const double err_P =
        best_relative_error(m.pk1(F), [&](double eps) { return fd_gradient([&](const Mat3& G) { return m.psi(G); }, F, eps); });
    const double err_H =
        best_relative_error(m.hessian(F), [&](double eps) { return fd_jacobian([&](const Mat3& G) { return m.pk1(G); }, F, eps); });
    EXPECT_LE(err_P, 1e-6) << "sample " << i;
    EXPECT_LE(err_H, 1e-6) << "sample " << i;
    // A projected inner Hessian stays PSD through the congruence.
    EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat9>(m.hessian(F, PsdProjection::clamp)).eigenvalues().minCoeff(), -1e-10);
  }
}

TEST(ActiveStrain, AFreeElementSettlesExactlyAtTheActiveShape) {
  // Nothing holds the element: Newton on its 9 entries from F = I (projected Hessian, backtracking on ψ)
  // ends at a rest where P = 0, and there F = R F_a: the fibre's length is 1 − α, the volume 1, ψ = 0.
  std::mt19937_64 rng(79);
  for (const double alpha : {0.1, 0.3, 0.5}) {
    Muscle m;
    m.a = random_unit(rng);
    m.active = ActiveStrain::along(m.a, alpha);
    Mat3 F = Mat3::Identity();
    int iterations = 0;
    for (; iterations < 100 && m.pk1(F).norm() > 1e-12; ++iterations) {
      // The rigid rotations are a null space: a tiny shift makes the system solvable, as pins would.
      const Mat9 H = m.hessian(F, PsdProjection::clamp) + 1e-9 * Mat9::Identity();
      const Vec9 step = -H.ldlt().solve(vec(m.pk1(F)));
      double t = 1.0;
      while (t > 1e-12 && !(m.psi(F + t * unvec(step)) <= m.psi(F))) t *= 0.5;
      F += t * unvec(step);
    }
    EXPECT_LT(iterations, 100) << "alpha " << alpha;
    EXPECT_LE(m.pk1(F).norm(), 1e-12) << "alpha " << alpha;
    EXPECT_NEAR((F * m.a).norm(), 1.0 - alpha, 1e-10) << "alpha " << alpha;
    EXPECT_NEAR(F.determinant(), 1.0, 1e-10) << "alpha " << alpha;
    EXPECT_NEAR(m.psi(F), 0.0, 1e-14) << "alpha " << alpha;  // rounding: Stable Neo-Hookean's ψ(I) is 0 to ~1e-16 (μ + λ = 11)
    // F F_a⁻¹ is a rotation.
    const Mat3 R = m.active.elastic(F);
    EXPECT_LE((R.transpose() * R - Mat3::Identity()).norm(), 1e-10) << "alpha " << alpha;
  }
}

}  // namespace
}  // namespace snh
