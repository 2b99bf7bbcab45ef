// The paper's properties per energy: rest stability, the linear limit under Lamé reparametrization,
// reflection consistency, explicit reporting of undefined states (never NaN), and the registry.
#include <gtest/gtest.h>

#include <cmath>

#include "energies.hpp"

#include <random>

#include "snh/material/printable.hpp"
#include "snh/material/registry.hpp"

namespace snh {
namespace {

template <class M>
class Properties : public ::testing::Test {};
TYPED_TEST_SUITE(Properties, test::AllEnergies);

template <class M>
constexpr bool is_rest_stable() {
  return !std::is_same_v<M, PsiD>;
}

TYPED_TEST(Properties, RestStability) {
  for (const Lame& p : test::parameter_sets()) {
    const TypeParam m(p);
    const Mat3 P = m.pk1(Mat3::Identity());
    if constexpr (is_rest_stable<TypeParam>()) {
      EXPECT_LE(P.norm(), 1e-13 * (p.mu + p.lambda)) << TypeParam::name;
    } else {
      EXPECT_LE((P - p.mu * Mat3::Identity()).norm(), 1e-13 * p.mu) << "psi_d: P(I) = mu I";
    }
    // Energies report ψ(I) = 0 where the formula allows a constant.
    EXPECT_NEAR(m.psi(Mat3::Identity()), 0.0, 1e-12 * (p.mu + p.lambda)) << TypeParam::name;
  }
}

TYPED_TEST(Properties, LinearLimitWithReparametrization) {
  const Vec9 v = vec(Mat3::Identity());
  const Mat9 T = transpose_permutation();
  for (const Lame& lin : test::parameter_sets()) {
    if constexpr (std::is_same_v<TypeParam, PsiD> || std::is_same_v<TypeParam, Arap>) {
      EXPECT_THROW((void)TypeParam::from_linear(lin), ParameterError);
      EXPECT_THROW((void)make_material(TypeParam::name, lin, true), ParameterError);
    } else {
      const TypeParam m(TypeParam::from_linear(lin));
      const Mat9 expected = lin.mu * (Mat9::Identity() + T) + lin.lambda * v * v.transpose();
      const Mat9 H = m.hessian(Mat3::Identity());
      EXPECT_LE((H - expected).norm(), 1e-10 * expected.norm()) << TypeParam::name << "\n" << H;
      // The registry applies the same mapping.
      std::visit([&](const auto& r) { EXPECT_LE((r.hessian(Mat3::Identity()) - expected).norm(), 1e-10 * expected.norm()); },
                 make_material(TypeParam::name, lin, true));
    }
  }
}

TYPED_TEST(Properties, ReflectionConsistency) {
  // ψ, P and the projected Hessian do not change when the SVD puts the negative sign on another σ.
  // corotated and arap use I1 = Σσ, which does change: the test asserts that they are *not* consistent.
  std::mt19937_64 rng(77);
  if constexpr (!TypeParam::inversion_safe) {
    // Undefined wherever the reflection is carried.
    const TypeParam m(test::parameter_sets()[0]);
    for (int i = 0; i < 20; ++i) {
      const Svd3 base = rotation_variant_svd(test::sample_F(rng, 0.2, 1.8, 1));
      for (int k = 0; k < 3; ++k) {
        const Svd3 moved = move_reflection(base, k);
        EXPECT_EQ(psi(m, moved), std::numeric_limits<double>::infinity());
        EXPECT_TRUE(projected_hessian(m, moved, PsdProjection::clamp).isZero());
      }
    }
  } else {
    const TypeParam m(test::parameter_sets()[0]);
    double worst = 0.0;
    for (int i = 0; i < 200; ++i) {
      const Mat3 F = test::sample_F(rng, 0.2, 1.8, 1 + 2 * (i % 2));  // one or three negative
      const Svd3 base = rotation_variant_svd(F);
      ASSERT_LT(base.sigma[2], 0.0);
      const Mat9 H0 = projected_hessian(m, base, PsdProjection::clamp);
      for (int k = 0; k < 2; ++k) {
        const Svd3 moved = move_reflection(base, k);
        const double scale_H = std::max(1.0, H0.norm());
        worst = std::max({worst, std::abs(psi(m, moved) - psi(m, base)) / std::max(1.0, std::abs(psi(m, base))),
                          (pk1(m, moved) - pk1(m, base)).norm() / std::max(1.0, pk1(m, base).norm()),
                          (projected_hessian(m, moved, PsdProjection::clamp) - H0).norm() / scale_H});
      }
    }
    if constexpr (test::uses_trace_of_S<TypeParam>()) {
      EXPECT_GT(worst, 1e-2) << TypeParam::name << " was expected to depend on where the reflection is";
    } else {
      EXPECT_LE(worst, 1e-12) << TypeParam::name;
    }
  }
}

TYPED_TEST(Properties, UndefinedStatesAreReportedNotNaN) {
  const TypeParam m(test::parameter_sets()[0]);
  std::mt19937_64 rng(88);
  std::vector<Mat3> cases = {Mat3::Zero(), -Mat3::Identity(), Mat3(Vec3(1, 1, -1).asDiagonal()),
                             Mat3(Vec3(1, 0, 1).asDiagonal())};
  for (int i = 0; i < 20; ++i) cases.push_back(test::sample_F(rng, 0.2, 1.5, 1));
  for (const Mat3& F : cases) {
    for (PsdProjection p : {PsdProjection::none, PsdProjection::clamp, PsdProjection::abs}) {
      const Evaluation e = evaluate(m, F, p);
      EXPECT_FALSE(std::isnan(e.psi)) << TypeParam::name;
      EXPECT_TRUE(e.P.allFinite() && e.H.allFinite()) << TypeParam::name;
      if (TypeParam::inversion_safe) {
        EXPECT_TRUE(e.defined);
        EXPECT_TRUE(std::isfinite(e.psi));
      } else {
        EXPECT_FALSE(e.defined) << TypeParam::name << " at J = " << F.determinant();
        EXPECT_EQ(e.psi, std::numeric_limits<double>::infinity());
        EXPECT_EQ(m.psi(F), std::numeric_limits<double>::infinity());
        EXPECT_TRUE(e.P.isZero() && e.H.isZero());
      }
    }
  }
}

TEST(Properties, PsiEEqualsProductionStableNeoHookean) {
  std::mt19937_64 rng(99);
  for (const Lame& p : test::parameter_sets()) {
    const StableNeoHookean snh(p);
    const PsiE e(p);
    for (int i = 0; i < 50; ++i) {
      const Mat3 F = test::sample_F(rng, 0.2, 1.8, i % 4);
      EXPECT_NEAR(snh.psi(F), e.psi(F), 1e-12 * std::max(1.0, std::abs(e.psi(F))));
      EXPECT_LE((snh.pk1(F) - e.pk1(F)).norm(), 1e-12 * std::max(1.0, e.pk1(F).norm()));
    }
  }
}

TEST(Properties, LogAlphaMakesRestStable) {
  // docs/math.md §1: α = 1 + 3μ/(4λ) (the thesis' α = 1 + μ/λ − (μ/4)λ is a typo).
  const StableNeoHookeanLog m({1.0, 10.0});
  EXPECT_DOUBLE_EQ(m.alpha, 1.075);
  const StableNeoHookean prod({1.0, 10.0});
  EXPECT_DOUBLE_EQ(prod.alpha, 1.1);
}

TEST(Registry, NamesAndErrors) {
  const auto& names = material_names();
  ASSERT_EQ(names.size(), 11u);
  for (auto n : names) EXPECT_EQ(name_of(make_material(n, {1.0, 10.0})), n);
  try {
    (void)make_material("stable_neohookean", {1.0, 10.0});
    FAIL() << "no exception";
  } catch (const UnknownMaterial& e) {
    EXPECT_NE(std::string(e.what()).find("unknown material 'stable_neohookean'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("stable_neo_hookean_log"), std::string::npos);
  }
  // Issue 13: a NUL byte in the name cut the message there (what() is a C string); control bytes are escaped.
  try {
    (void)make_material(std::string("stable\0neo\x1b[2J", 14), {1.0, 10.0});
    FAIL() << "no exception";
  } catch (const UnknownMaterial& e) {
    EXPECT_NE(std::string(e.what()).find("unknown material 'stable\\x00neo\\x1b[2J' (known: stable_neo_hookean"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(printable(std::string("a\0b\\c\n\xff", 7)), "a\\x00b\\\\c\\x0a\\xff");
  EXPECT_THROW((void)make_material("stable_neo_hookean", {0.0, 10.0}), ParameterError);
  EXPECT_THROW((void)make_material("stable_neo_hookean", {1.0, std::nan("")}), ParameterError);
  EXPECT_THROW((void)make_material("stable_neo_hookean", {1.0, -0.1}), ParameterError);  // alpha needs lambda > 0
  EXPECT_THROW((void)make_material("neo_hookean", {-1.0, 10.0}), ParameterError);
}

}  // namespace
}  // namespace snh

namespace snh {
namespace {

/// ψ, P and ∂P/∂F but no route to an eigensystem: not a Material (the PSD projection could not use it).
struct NoEigensystem {
  static constexpr std::string_view name = "none", formula = "";
  static constexpr bool inversion_safe = true;
  static Lame from_linear(const Lame& l) { return l; }
  Lame params() const { return {}; }
  bool defined(const Mat3&) const { return true; }
  double psi(const Mat3&) const { return 0.0; }
  Mat3 pk1(const Mat3&) const { return Mat3::Zero(); }
  Mat9 hessian(const Mat3&) const { return Mat9::Zero(); }
};
struct WithOwnEigensystem : NoEigensystem {
  Eigensystem9 eigensystem() const { return {}; }
};
static_assert(!Material<NoEigensystem>, "a material needs one of the two eigensystem routes");
static_assert(Material<WithOwnEigensystem> && !IsotropicMaterial<WithOwnEigensystem>);
static_assert(IsotropicMaterial<Corotated> && IsotropicMaterial<StableNeoHookean> && Material<Linear>);

/// point_terms (one SVD) gives what the separate calls give, bit for bit, for every energy and projection.
TEST(PointTerms, EqualTheSeparateCallsBitForBit) {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> n(0.0, 0.6);
  for (std::string_view name : material_names()) {
    const AnyMaterial any = make_material(name, {1.0, 10.0});
    std::visit(
        [&](const auto& m) {
          for (int k = 0; k < 50; ++k) {
            Mat3 F = Mat3::Identity();
            for (int i = 0; i < 9; ++i) F.data()[i] += n(rng);
            if (!m.defined(F)) F.col(0) *= -1.0;
            for (PsdProjection p : {PsdProjection::none, PsdProjection::clamp, PsdProjection::abs}) {
              const PointTerms t = point_terms(m, F, true, true, p);
              EXPECT_EQ(t.psi, m.psi(F)) << name;
              EXPECT_EQ(t.P, m.pk1(F)) << name;
              EXPECT_EQ(t.H, projected_hessian(m, F, p)) << name << " " << to_string(p);
            }
          }
        },
        any);
  }
}

}  // namespace
}  // namespace snh
