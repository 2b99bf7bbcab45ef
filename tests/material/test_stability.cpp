// The measured stability table agrees with docs/math.md §1 and §5, and its collapse analysis finds the
// critical points that the closed-form polynomials predict.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "snh/material/stability.hpp"

namespace snh {
namespace {

struct Expected {
  bool defined_inverted;  // docs/math.md §1 "defined for J ≤ 0"
  bool reflection;        // independent of where the reflection sits
  bool rest;              // docs/math.md §1 "rest-stable"
};

const std::map<std::string, Expected>& expectations() {
  static const std::map<std::string, Expected> e = {
      {"stable_neo_hookean", {true, true, true}}, {"stable_neo_hookean_log", {true, true, true}},
      {"neo_hookean", {false, false, true}},      {"neo_hookean_a", {false, false, true}},
      {"neo_hookean_b", {false, false, true}},    {"psi_d", {true, true, false}},
      {"psi_e", {true, true, true}},              {"corotated", {true, false, true}},
      {"arap", {true, false, true}},              {"stvk", {true, true, true}},
      {"linear", {true, true, true}}};
  return e;
}

const StabilityRow& row(const StabilityReport& r, const std::string& name) {
  for (const auto& x : r.rows)
    if (x.name == name) return x;
  throw std::runtime_error("no row " + name);
}

/// The root in (0, 1) of s⁴ − αs + c = 0 below the one at s = 1 (bisection on an independent formula).
double quartic_root(double alpha, double c, double lo, double hi) {
  auto f = [&](double s) { return s * s * s * s - alpha * s + c; };
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    ((f(lo) < 0) == (f(mid) < 0) ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(Stability, TableAgreesWithMathMd) {
  const StabilityReport rep = measure_stability({1.0, 10.0}, false, 100, 3);
  ASSERT_EQ(rep.rows.size(), expectations().size());
  for (const auto& r : rep.rows) {
    const Expected& e = expectations().at(r.name);
    EXPECT_EQ(r.inversion_ok, e.defined_inverted) << r.name;
    EXPECT_EQ(r.inverted_finite == r.inverted_samples, e.defined_inverted) << r.name;
    if (!e.defined_inverted) {
      EXPECT_EQ(r.inverted_finite, 0) << r.name;
    }
    EXPECT_EQ(r.reflection_ok, e.reflection) << r.name;
    EXPECT_EQ(r.rest_ok, e.rest) << r.name;
    EXPECT_NEAR(r.psi_at_rest, 0.0, 1e-12) << r.name;
  }
  EXPECT_NEAR(row(rep, "psi_d").rest_stress, std::sqrt(3.0), 1e-12);  // ‖μI‖ with μ = 1
}

TEST(Stability, CollapsePathProductionHasTrapLogDoesNot) {
  // Reparametrized from ν = 0.4 (λ_L = 4μ_L): production μ = 1, λ = 5, α = 1.2, barrier at the root of
  // s⁴ − αs + μ/λ near 0.167 (docs/math.md §5); the log form has no critical point and F = 0 is not a trap.
  const StabilityReport rep = measure_stability({1.0, 4.0}, true, 20, 1);
  const StabilityRow& prod = row(rep, "stable_neo_hookean");
  ASSERT_EQ(prod.critical_points.size(), 1u);
  EXPECT_FALSE(prod.critical_points[0].minimum);
  EXPECT_NEAR(prod.critical_points[0].s, quartic_root(1.2, 0.2, 0.0, 0.5), 1e-9);
  EXPECT_NEAR(prod.critical_points[0].s, 0.167, 2e-3);
  EXPECT_EQ(prod.near_zero.rfind("trap", 0), 0u);
  const StabilityRow& log = row(rep, "stable_neo_hookean_log");
  EXPECT_TRUE(log.critical_points.empty());
  EXPECT_EQ(log.near_zero.rfind("escapes", 0), 0u);
  EXPECT_TRUE(std::isfinite(log.psi_at_zero));
}

TEST(Stability, TrapShrinksNearIncompressible) {
  // ν = 0.488: λ_L/μ_L = 0.976/0.024; production barrier near 0.023 (docs/math.md §5).
  const double ratio = 2 * 0.488 / (1 - 2 * 0.488);
  const StabilityReport rep = measure_stability({1.0, ratio}, true, 10, 1);
  const StabilityRow& prod = row(rep, "stable_neo_hookean");
  ASSERT_EQ(prod.critical_points.size(), 1u);
  EXPECT_NEAR(prod.critical_points[0].s, 0.023, 1e-3);
}

TEST(Stability, PsiDShrinksToItsRestingPoint) {
  // ν = 0.4 as given (λ = 4μ): ψ_D's minimum along F = sI is the root of s⁴ − s + μ/λ near 0.897
  // (docs/math.md §5), with a barrier near μ/λ.
  const StabilityReport rep = measure_stability({1.0, 4.0}, false, 10, 1);
  const StabilityRow& d = row(rep, "psi_d");
  ASSERT_EQ(d.critical_points.size(), 2u);
  EXPECT_FALSE(d.critical_points[0].minimum);
  EXPECT_TRUE(d.critical_points[1].minimum);
  EXPECT_NEAR(d.critical_points[1].s, quartic_root(1.0, 0.25, 0.5, 0.99), 1e-9);
  EXPECT_NEAR(d.critical_points[1].s, 0.897, 1e-3);
}

TEST(Stability, LogEnergiesHaveABarrierAtZero) {
  const StabilityReport rep = measure_stability({1.0, 10.0}, false, 10, 1);
  for (const char* name : {"neo_hookean", "neo_hookean_a", "neo_hookean_b"}) {
    const StabilityRow& r = row(rep, name);
    EXPECT_TRUE(r.critical_points.empty()) << name;
    EXPECT_EQ(r.psi_at_zero, std::numeric_limits<double>::infinity()) << name;
    EXPECT_EQ(r.near_zero, "psi->inf") << name;
  }
}

TEST(Stability, RejectsInvalidParameters) {
  EXPECT_THROW((void)measure_stability({-1.0, 10.0}, false), ParameterError);
}

}  // namespace
}  // namespace snh
