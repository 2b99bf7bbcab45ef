// Micro-benchmarks of the multigrid V-cycle (issue 15): one V-cycle application (M⁻¹ r) and one product A p,
// as conjugate gradients calls them, on a stable Neo-Hookean Hessian (ν = 0.45, projected) of a box lattice
// of hexes (mg) or tets (amg) at the resolution given, near rest with a random perturbation, its bottom face
// pinned; the thread count is the second argument (1 and 2: the results are bit-identical, the times not).
// Timings on a shared machine are noisy: run with --benchmark_repetitions and read the minimum.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <memory>
#include <random>
#include <stdexcept>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/solve/multigrid.hpp"

namespace {

struct Setup {
  Setup(snh::CellType type, int res)
      : mesh(type == snh::CellType::tet4 ? snh::box_tets(res) : snh::box_hexes(res)),
        elastic(mesh, snh::make_material("stable_neo_hookean", snh::Lame{1.0, 9.0})),
        problem{snh::DofMap(pinned(mesh))},
        vcycle(mesh, problem.dofs().free_index(), type == snh::CellType::tet4 ? snh::Coarsening::aggregation : snh::Coarsening::lattice) {
    problem.add(elastic);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size()), g;
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += 0.1 / res * u(rng);
    snh::HessianMatrix H;
    problem.evaluate(x, g, &H, snh::PsdProjection::clamp);
    if (!vcycle.compute(H.matrix)) throw std::runtime_error("bench_multigrid: the V-cycle failed");
    r.resize(H.matrix.rows());
    for (Eigen::Index i = 0; i < r.size(); ++i) r[i] = u(rng);
  }
  static std::vector<std::uint8_t> pinned(const snh::VolumeMesh& m) {
    std::vector<std::uint8_t> out(3 * m.vertex_count(), 0);
    const double low = m.vertices.row(1).minCoeff();
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      if (m.vertices(1, v) == low) out[3 * v] = out[3 * v + 1] = out[3 * v + 2] = 1;
    return out;
  }
  snh::VolumeMesh mesh;
  snh::ElasticTerm elastic;
  snh::Problem problem;
  snh::MultigridPreconditioner vcycle;
  Eigen::VectorXd r, z;
};

void BM_Multigrid(benchmark::State& state, snh::CellType type, bool product) {
  const int threads = omp_get_max_threads();
  static std::unique_ptr<Setup> s;
  static std::pair<snh::CellType, int> made{};
  if (!s || made != std::pair{type, static_cast<int>(state.range(0))}) {
    s = std::make_unique<Setup>(type, static_cast<int>(state.range(0)));
    made = {type, static_cast<int>(state.range(0))};
  }
  omp_set_num_threads(static_cast<int>(state.range(1)));
  for (auto _ : state) {
    if (product) s->vcycle.multiply(s->r, s->z);
    else s->vcycle.apply(s->r, s->z);
    benchmark::DoNotOptimize(s->z.data());
  }
  omp_set_num_threads(threads);
  state.counters["dofs"] = static_cast<double>(s->r.size());
}
const auto min = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
BENCHMARK_CAPTURE(BM_Multigrid, hex_vcycle, snh::CellType::hex8, false)->Args({30, 1})->Args({30, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, hex_product, snh::CellType::hex8, true)->Args({30, 1})->Args({30, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, tet_vcycle, snh::CellType::tet4, false)->Args({20, 1})->Args({20, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, tet_product, snh::CellType::tet4, true)->Args({20, 1})->Args({20, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);

}  // namespace

BENCHMARK_MAIN();
