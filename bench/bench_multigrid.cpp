// Micro-benchmarks of the multigrid V-cycle (issue 15): one V-cycle application (M⁻¹ r) and one product A p,
// as conjugate gradients calls them, on a stable Neo-Hookean Hessian (ν = 0.45, projected) of a box lattice
// of hexes (mg) or tets (amg) at the resolution given, near rest with a random perturbation, its bottom face
// pinned; the thread count is the second argument (1 and 2: the results are bit-identical, the times not).
// Timings on a shared machine are noisy: run with --benchmark_repetitions and read the minimum.
//
// BM_ProductForm (issue 34: "a more compact matrix or a matrix-free product; measure which") times other
// forms of the same hex product on one thread, beside the V-cycle's own (hex_product): the lower block
// triangle in single precision (3×3 blocks, one column index each, each block used for itself and its
// transpose), and element by element from stored 24×24 element matrices in single precision (their upper
// triangles, 300 floats each: the least a product from stored element data can read). The element matrices'
// values are random, as they do not change the time; a product that recomputes the material's Hessian at
// each quadrature point instead reads nothing but costs an assembly (bench_assembly).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <array>
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
/// The lower block triangle of `H` (free DOFs; all three of a node's DOFs free or none) in single precision.
struct FloatBlocks {
  explicit FloatBlocks(const snh::SparseLower& H) : nodes(static_cast<int>(H.rows() / 3)) {
    std::vector<std::vector<std::pair<int, std::array<float, 9>>>> rows(nodes);
    for (Eigen::Index c = 0; c < H.outerSize(); ++c)
      for (snh::SparseLower::InnerIterator it(H, c); it; ++it) {
        const int i = static_cast<int>(it.row() / 3), j = static_cast<int>(c / 3);
        auto& row = rows[i];
        auto at = std::find_if(row.begin(), row.end(), [j](const auto& b) { return b.first == j; });
        if (at == row.end()) at = row.insert(row.end(), {j, std::array<float, 9>{}});
        at->second[3 * (it.row() % 3) + c % 3] = static_cast<float>(it.value());
      }
    start.push_back(0);
    for (auto& row : rows) {
      std::sort(row.begin(), row.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      for (const auto& [j, block] : row) {
        col.push_back(j);
        val.insert(val.end(), block.begin(), block.end());
      }
      start.push_back(static_cast<int>(col.size()));
    }
  }
  /// y = A x: each stored block (i, j), j < i, for itself and its transpose; the diagonal block once (its
  /// upper half taken from the lower by symmetry).
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    y.setZero(x.size());
    for (int i = 0; i < nodes; ++i) {
      const double* xi = x.data() + 3 * i;
      double yi[3] = {0.0, 0.0, 0.0};
      for (int k = start[i]; k < start[i + 1]; ++k) {
        const float* a = val.data() + 9 * static_cast<std::size_t>(k);
        const int j = col[k];
        const double* xj = x.data() + 3 * j;
        if (j == i) {
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) yi[r] += (c <= r ? a[3 * r + c] : a[3 * c + r]) * xi[c];
          continue;
        }
        double* yj = y.data() + 3 * j;
        for (int r = 0; r < 3; ++r) {
          yi[r] += a[3 * r] * xj[0] + a[3 * r + 1] * xj[1] + a[3 * r + 2] * xj[2];
          for (int c = 0; c < 3; ++c) yj[c] += a[3 * r + c] * xi[r];
        }
      }
      for (int r = 0; r < 3; ++r) y[3 * i + r] += yi[r];
    }
  }
  int nodes;
  std::vector<int> start, col;
  std::vector<float> val;
};

/// y = Σ_e K_e x_e from stored element matrices (upper triangles in single precision, by rows).
struct ElementMatrices {
  ElementMatrices(const snh::VolumeMesh& mesh, std::mt19937_64& rng) : cells(mesh.cells) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    upper.resize(300 * static_cast<std::size_t>(mesh.cell_count()));
    for (float& v : upper) v = u(rng);
  }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& y) const {
    y.setZero(x.size());
    for (Eigen::Index e = 0; e < cells.cols(); ++e) {
      double xe[24], ye[24] = {};
      for (int k = 0; k < 8; ++k)
        for (int a = 0; a < 3; ++a) xe[3 * k + a] = x[3 * cells(k, e) + a];
      const float* K = upper.data() + 300 * static_cast<std::size_t>(e);
      for (int r = 0; r < 24; ++r) {
        ye[r] += *K++ * xe[r];
        for (int c = r + 1; c < 24; ++c, ++K) ye[r] += *K * xe[c], ye[c] += *K * xe[r];
      }
      for (int k = 0; k < 8; ++k)
        for (int a = 0; a < 3; ++a) y[3 * cells(k, e) + a] += ye[3 * k + a];
    }
  }
  Eigen::Matrix<int, 8, Eigen::Dynamic> cells;
  std::vector<float> upper;
};

/// `form`: 0 the lower block triangle in single precision, 1 element by element from stored matrices.
void BM_ProductForm(benchmark::State& state, int form) {
  const int res = static_cast<int>(state.range(0));
  const snh::VolumeMesh mesh = snh::box_hexes(res);
  Eigen::VectorXd x, y;
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::unique_ptr<FloatBlocks> blocks;
  std::unique_ptr<ElementMatrices> elements;
  double bytes = 0.0;
  if (form == 0) {
    snh::ElasticTerm elastic(mesh, snh::make_material("stable_neo_hookean", snh::Lame{1.0, 9.0}));
    snh::Problem problem{snh::DofMap(std::vector<std::uint8_t>(3 * mesh.vertex_count(), 0))};
    problem.add(elastic);
    const Eigen::VectorXd at = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size());
    Eigen::VectorXd g;
    snh::HessianMatrix H;
    problem.evaluate(at, g, &H, snh::PsdProjection::clamp);
    blocks = std::make_unique<FloatBlocks>(H.matrix);
    bytes = 36.0 * static_cast<double>(blocks->col.size()) + 4.0 * static_cast<double>(blocks->col.size());
    x.resize(H.matrix.rows());
  } else {
    elements = std::make_unique<ElementMatrices>(mesh, rng);
    bytes = 4.0 * static_cast<double>(elements->upper.size()) + 32.0 * static_cast<double>(mesh.cell_count());
    x.resize(3 * mesh.vertex_count());
  }
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = u(rng);
  for (auto _ : state) {
    if (blocks) blocks->multiply(x, y);
    else elements->multiply(x, y);
    benchmark::DoNotOptimize(y.data());
  }
  state.counters["dofs"] = static_cast<double>(x.size());
  state.counters["MB"] = bytes / 1e6;  // the matrix data one product reads (values and indices)
}

const auto min = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
BENCHMARK_CAPTURE(BM_Multigrid, hex_vcycle, snh::CellType::hex8, false)->Args({30, 1})->Args({30, 2})->Args({45, 1})->Args({45, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, hex_product, snh::CellType::hex8, true)->Args({30, 1})->Args({30, 2})->Args({45, 1})->Args({45, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_ProductForm, hex_float_blocks, 0)->Arg(30)->Arg(45)->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_ProductForm, hex_float_elements, 1)->Arg(30)->Arg(45)->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, tet_vcycle, snh::CellType::tet4, false)->Args({20, 1})->Args({20, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);
BENCHMARK_CAPTURE(BM_Multigrid, tet_product, snh::CellType::tet4, true)->Args({20, 1})->Args({20, 2})->Unit(benchmark::kMillisecond)->ComputeStatistics("min", min);

}  // namespace

BENCHMARK_MAIN();
