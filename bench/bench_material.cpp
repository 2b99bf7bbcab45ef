// Micro-benchmarks of the energies: ψ, P and the projected 9x9 Hessian (SVD included) per call,
// one core. Inputs cycle through 1024 random F (half of them inverted) so branch prediction and
// caches see realistic variety.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "snh/material/registry.hpp"
#include "snh/math/random.hpp"
#include "snh/math/svd.hpp"

namespace {

/// 1024 random F per input set. Set 0, "moderate": σ in [0.7, 1.4], J > 0 (the usual state of a
/// simulation element). Set 1, "inverted": σ in [0.3, 1.7] with one negative σ (the hard case: the
/// scaling block is often indefinite and needs its own eigen-decomposition).
const std::vector<snh::Mat3>& inputs(int set) {
  static const std::vector<snh::Mat3> sets[2] = {
      [] {
        std::mt19937_64 rng(42);
        std::uniform_real_distribution<double> mag(0.7, 1.4);
        std::vector<snh::Mat3> out;
        for (int i = 0; i < 1024; ++i) out.push_back(snh::random_matrix_with_sigma(rng, snh::Vec3(mag(rng), mag(rng), mag(rng))));
        return out;
      }(),
      [] {
        std::mt19937_64 rng(43);
        std::uniform_real_distribution<double> mag(0.3, 1.7);
        std::vector<snh::Mat3> out;
        for (int i = 0; i < 1024; ++i) {
          snh::Vec3 s(mag(rng), mag(rng), mag(rng));
          s[i % 3] = -s[i % 3];
          out.push_back(snh::random_matrix_with_sigma(rng, s));
        }
        return out;
      }()};
  return sets[set];
}

const snh::Lame kParams{1.0, 10.0};

void BM_Svd(benchmark::State& state) {
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(snh::rotation_variant_svd(Fs[i++ & 1023]));
  }
}
BENCHMARK(BM_Svd)->ArgName("inverted")->Arg(0)->Arg(1);

void BM_SymmetricEigen3(benchmark::State& state) {
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) {
    const snh::Mat3& F = Fs[i++ & 1023];
    benchmark::DoNotOptimize(snh::symmetric_eigen3(F + F.transpose()));
  }
}
BENCHMARK(BM_SymmetricEigen3)->ArgName("inverted")->Arg(0)->Arg(1);

void BM_Rebuild(benchmark::State& state) {
  const snh::StableNeoHookean m(kParams);
  std::vector<snh::Eigensystem9> es;
  for (const auto& F : inputs(static_cast<int>(state.range(0)))) es.push_back(snh::eigensystem(m, snh::rotation_variant_svd(F)));
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(snh::rebuild(es[i++ & 1023], snh::PsdProjection::clamp));
}
BENCHMARK(BM_Rebuild)->ArgName("inverted")->Arg(0)->Arg(1);

template <class M>
void BM_Psi(benchmark::State& state) {
  const M m(kParams);
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(m.psi(Fs[i++ & 1023]));
}

template <class M>
void BM_PK1(benchmark::State& state) {
  const M m(kParams);
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(m.pk1(Fs[i++ & 1023]));
}

template <class M>
void BM_Hessian(benchmark::State& state) {
  const M m(kParams);
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(m.hessian(Fs[i++ & 1023]));
}

template <class M>
void BM_ProjectedHessian(benchmark::State& state) {
  const M m(kParams);
  const auto& Fs = inputs(static_cast<int>(state.range(0)));
  std::size_t i = 0;
  for (auto _ : state)
    benchmark::DoNotOptimize(snh::projected_hessian(m, Fs[i++ & 1023], snh::PsdProjection::clamp));
}

BENCHMARK_TEMPLATE(BM_Psi, snh::StableNeoHookean)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_PK1, snh::StableNeoHookean)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_Hessian, snh::StableNeoHookean)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_ProjectedHessian, snh::StableNeoHookean)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_Psi, snh::StableNeoHookeanLog)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_PK1, snh::StableNeoHookeanLog)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_Hessian, snh::StableNeoHookeanLog)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_ProjectedHessian, snh::StableNeoHookeanLog)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_ProjectedHessian, snh::Corotated)->ArgName("inverted")->Arg(0)->Arg(1);
BENCHMARK_TEMPLATE(BM_ProjectedHessian, snh::StVK)->ArgName("inverted")->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();
