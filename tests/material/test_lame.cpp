// Lamé parameters: E/ν conversion, Poisson's ratio, validation messages, and the reparametrizations
// of docs/math.md §2.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "snh/material/lame.hpp"
#include "snh/material/stable_neo_hookean.hpp"
#include "snh/material/stable_neo_hookean_log.hpp"

namespace snh {
namespace {

TEST(Lame, FromYoungsAndPoisson) {
  const Lame p = lame_from_youngs(1000.0, 0.3);
  EXPECT_NEAR(p.mu, 1000.0 / 2.6, 1e-12);
  EXPECT_NEAR(p.lambda, 300.0 / (1.3 * 0.4), 1e-9);
  EXPECT_NEAR(poisson_ratio(p), 0.3, 1e-14);
  EXPECT_NEAR(youngs_modulus(p), 1000.0, 1e-9);
}

TEST(Lame, ThesisExamplePoissonRatio) {
  // μ = 1, λ = 10 gives ν = 10/22 = 0.4545 (docs/math.md §2).
  EXPECT_NEAR(poisson_ratio({1.0, 10.0}), 10.0 / 22.0, 1e-15);
}

std::string message_of(auto&& f) {
  try {
    f();
  } catch (const ParameterError& e) {
    return e.what();
  }
  return "";
}

TEST(Lame, InvalidParametersNameTheProblem) {
  EXPECT_NE(message_of([] { validate({0.0, 1.0}); }).find("mu must be"), std::string::npos);
  EXPECT_NE(message_of([] { validate({-2.0, 1.0}); }).find("-2"), std::string::npos);
  EXPECT_NE(message_of([] { validate({std::nan(""), 1.0}); }).find("mu"), std::string::npos);
  EXPECT_NE(message_of([] { validate({1.0, std::nan("")}); }).find("lambda"), std::string::npos);
  EXPECT_NE(message_of([] { validate({1.0, -1.0}); }).find("bulk modulus"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(1.0, 0.5); }).find("Poisson"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(1.0, 0.7); }).find("0.7"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(1.0, -1.0); }).find("Poisson"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(0.0, 0.3); }).find("Young"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(std::nan(""), 0.3); }).find("Young"), std::string::npos);
  EXPECT_EQ(message_of([] { validate({1.0, 10.0}); }), "");
}

TEST(Lame, OutsideTheSupportedRangeIsRefusedNamingTheValue) {
  // Issue 13: mu = 1e300 printed psi = nan (alpha = 1 + mu/lambda, mu^2/lambda overflow).
  EXPECT_NE(message_of([] { validate({1e300, 10.0}); }).find("mu = 1e+300 is outside the supported range"),
            std::string::npos);
  EXPECT_NE(message_of([] { validate({1e-13, 10.0}); }).find("mu = 1e-13"), std::string::npos);
  EXPECT_NE(message_of([] { validate({1.0, 1e13}); }).find("lambda = 1e+13"), std::string::npos);
  EXPECT_NE(message_of([] { validate({1.0, 1e-300}); }).find("lambda = 1e-300"), std::string::npos);
  EXPECT_NE(message_of([] { (void)lame_from_youngs(1e300, 0.3); }).find("outside the supported range"),
            std::string::npos);
  EXPECT_EQ(message_of([] { validate({1e12, 1e12}); }), "");
  EXPECT_EQ(message_of([] { validate({1e-12, -1e-13 + 1e-13}); }), "");  // lambda = 0
  EXPECT_EQ(message_of([] { validate({1e-12, 1e-12}); }), "");
  // At the edges every energy's psi, P and eigenvalues stay finite at F within the supported entries.
  for (const Lame p : {Lame{1e12, 1e12}, Lame{1e-12, 1e-12}, Lame{1e12, 1e-12}}) {
    const StableNeoHookean m(p);
    for (double f : {1e-20, 1.0, 1e20}) {
      const Mat3 F = Vec3(f, 1.0, f).asDiagonal();
      EXPECT_TRUE(std::isfinite(m.psi(F))) << f;
      EXPECT_TRUE(m.pk1(F).allFinite()) << f;
    }
  }
}

TEST(Lame, Reparametrizations) {
  const Lame lin{3.0, 12.0};
  const Lame prod = StableNeoHookean::from_linear(lin);
  EXPECT_DOUBLE_EQ(prod.mu, 3.0);
  EXPECT_DOUBLE_EQ(prod.lambda, 15.0);
  const Lame log = StableNeoHookeanLog::from_linear(lin);
  EXPECT_DOUBLE_EQ(log.mu, 4.0);
  EXPECT_DOUBLE_EQ(log.lambda, 12.0 + 2.5);
}

}  // namespace
}  // namespace snh
