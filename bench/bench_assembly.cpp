// Micro-benchmarks of assembly: the stable Neo-Hookean elastic term of a [-1, 1]³ box lattice (hexes or
// tets, resolution given), stretched 1.5x along y with a small twist, its boundary fixed; energy alone (a
// line-search probe), energy and gradient, and energy, gradient and the projected Hessian (a Newton
// iteration's assembly) or the true one (the stretch test's). One thread unless SNH_BENCH_THREADS says otherwise (OpenMP's own setting).
#include <benchmark/benchmark.h>

#include <cmath>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"

namespace {

struct Setup {
  Setup(snh::CellType type, int res)
      : elastic(type == snh::CellType::tet4 ? snh::box_tets(res) : snh::box_hexes(res),
                snh::make_material("stable_neo_hookean", snh::Lame{1.0, 10.0})),
        problem{snh::DofMap(fixed(elastic.mesh()))} {
    problem.add(elastic);
    const auto& V = elastic.mesh().vertices;
    x.resize(V.size());
    for (Eigen::Index v = 0; v < V.cols(); ++v) {
      const double a = 0.3 * V(1, v);
      x.segment<3>(3 * v) << std::cos(a) * V(0, v) - std::sin(a) * V(2, v), 1.5 * V(1, v),
          std::sin(a) * V(0, v) + std::cos(a) * V(2, v);
    }
  }
  static std::vector<std::uint8_t> fixed(const snh::VolumeMesh& m) {
    std::vector<std::uint8_t> out(3 * m.vertex_count(), 0);
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      if (m.vertices.col(v).cwiseAbs().maxCoeff() > 1.0 - 1e-9) out[3 * v] = out[3 * v + 1] = out[3 * v + 2] = 1;
    return out;
  }
  snh::ElasticTerm elastic;
  snh::Problem problem;
  Eigen::VectorXd x, g;
};

void BM_Assemble(benchmark::State& state, snh::CellType type, int what) {
  Setup s(type, static_cast<int>(state.range(0)));
  snh::HessianMatrix H;
  for (auto _ : state) {
    if (what == 0) benchmark::DoNotOptimize(s.problem.energy(s.x));
    else
      benchmark::DoNotOptimize(s.problem.evaluate(s.x, s.g, what >= 2 ? &H : nullptr,
                                                  what == 3 ? snh::PsdProjection::none : snh::PsdProjection::clamp));
  }
  state.counters["cells"] = static_cast<double>(s.elastic.mesh().cell_count());
  state.counters["us/cell"] = benchmark::Counter(static_cast<double>(s.elastic.mesh().cell_count()),
                                                 benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK_CAPTURE(BM_Assemble, hex_energy, snh::CellType::hex8, 0)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, hex_gradient, snh::CellType::hex8, 1)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, hex_hessian, snh::CellType::hex8, 2)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, hex_true_hessian, snh::CellType::hex8, 3)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, tet_energy, snh::CellType::tet4, 0)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, tet_gradient, snh::CellType::tet4, 1)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, tet_hessian, snh::CellType::tet4, 2)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Assemble, tet_true_hessian, snh::CellType::tet4, 3)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
