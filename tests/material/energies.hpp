#pragma once
// Shared fixtures for the material tests: the typed-test list of every energy, and samples of F.
#include <gtest/gtest.h>

#include <random>
#include <variant>
#include <vector>

#include "snh/material/registry.hpp"
#include "snh/math/random.hpp"

namespace snh::test {

template <class V>
struct TypesOf;
template <class... T>
struct TypesOf<std::variant<T...>> {
  using type = ::testing::Types<T...>;
};
/// Every registered energy, for TYPED_TEST_SUITE.
using AllEnergies = TypesOf<AnyMaterial>::type;

/// Parameter sets the tests sweep: the paper's example, a stiffer near-incompressible one, and a soft one.
inline const std::vector<Lame>& parameter_sets() {
  static const std::vector<Lame> sets = {{1.0, 10.0}, {2.5, 100.0}, {0.3, 0.8}};
  return sets;
}

/// Whether the energy depends on I1 = Σσ (corotated, arap): singular where σ_i + σ_j = 0.
template <class M>
constexpr bool uses_trace_of_S() {
  if constexpr (requires { M::uses_I1; }) return M::uses_I1;
  else return false;
}

/// Smallest |σ_i + σ_j| over the three pairs.
inline double min_pair_sum(const Vec3& s) {
  return std::min({std::abs(s[0] + s[1]), std::abs(s[1] + s[2]), std::abs(s[0] + s[2])});
}

/// Random F = U diag(σ) Vᵀ with |σ| in [lo, hi]; `negatives` of the σ are made negative.
inline Mat3 sample_F(std::mt19937_64& rng, double lo, double hi, int negatives, Vec3* sigma_out = nullptr) {
  std::uniform_real_distribution<double> mag(lo, hi);
  Vec3 s(mag(rng), mag(rng), mag(rng));
  for (int i = 0; i < negatives; ++i) s[i] = -s[i];
  if (sigma_out) *sigma_out = s;
  return random_matrix_with_sigma(rng, s);
}

}  // namespace snh::test
