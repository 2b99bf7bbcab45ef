// The elastic term assembled through a Problem: patch test, finite differences of the assembled gradient
// and Hessian on distorted meshes, PSD projection, bit-identical results for 1 and 2 threads, per-cell
// materials and weight scales, and bad input.
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <tuple>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/mesh/box.hpp"
#include "fem/problem_fd.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

/// A small box mesh with every vertex moved randomly by up to `jitter` of the spacing (general hexes).
VolumeMesh distorted(CellType type, int res, double jitter, unsigned seed) {
  VolumeMesh m = type == CellType::tet4 ? box_tets(res) : box_hexes(res);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double h = 2.0 / res;
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    for (int d = 0; d < 3; ++d) m.vertices(d, v) += jitter * h * u(rng);
  return m;
}

using test::flatten;

/// Boundary vertices of the (undistorted) lattice fixed, interior free.
std::vector<std::uint8_t> boundary_fixed(int res) {
  std::vector<std::uint8_t> fixed(3 * (res + 1) * (res + 1) * (res + 1), 0);
  for (int k = 0; k <= res; ++k)
    for (int j = 0; j <= res; ++j)
      for (int i = 0; i <= res; ++i)
        if (i == 0 || j == 0 || k == 0 || i == res || j == res || k == res)
          for (int d = 0; d < 3; ++d) fixed[3 * lattice_index(res, i, j, k) + d] = 1;
  return fixed;
}

/// An elastic term alone in a problem with these kinematic DOFs.
struct Assembled {
  Assembled(const VolumeMesh& m, AnyMaterial material, const std::vector<std::uint8_t>& fixed)
      : elastic(m, std::move(material)), problem{DofMap(fixed)} {
    problem.add(elastic);
  }
  /// Energy and free-DOF gradient; the free-DOF Hessian when H is given.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& g, SparseLower* H = nullptr,
                  PsdProjection p = PsdProjection::clamp) {
    HessianMatrix M;
    const double E = problem.evaluate(x, g, H ? &M : nullptr, p);
    if (H) *H = M.matrix;
    return E;
  }
  ElasticTerm elastic;
  Problem problem;
};

class Assembly : public ::testing::TestWithParam<std::tuple<CellType, std::string>> {};

TEST_P(Assembly, PatchTestAffineDeformationIsAnEquilibrium) {
  const auto [type, name] = GetParam();
  const int res = 3;
  const VolumeMesh m = distorted(type, res, 0.2, 1);
  Assembled sys(m, make_material(name, {1.0, 10.0}), boundary_fixed(res));
  Mat3 A;
  A << 1.3, 0.2, -0.1, 0.05, 0.8, 0.3, -0.2, 0.1, 1.1;
  const Eigen::Matrix3Xd X = (A * m.vertices).colwise() + Eigen::Vector3d(0.3, -0.2, 0.5);
  Eigen::VectorXd g;
  const double E = sys.evaluate(flatten(X), g, nullptr);
  ASSERT_GT(sys.problem.dofs().free_count(), 0);
  // Energy = rest volume × ψ(A); interior forces vanish.
  const double psi = std::visit([&](const auto& mat) { return mat.psi(A); }, sys.elastic.material(0));
  const double volume = rest_volumes(sys.elastic.rest()).sum();
  EXPECT_NEAR(E, volume * psi, 1e-12 * std::abs(volume * psi));
  const double scale = std::visit([&](const auto& mat) { return mat.pk1(A).norm(); }, sys.elastic.material(0));
  EXPECT_LE(g.norm(), 1e-12 * scale) << name;
}

TEST_P(Assembly, GradientAndHessianMatchFiniteDifferences) {
  const auto [type, name] = GetParam();
  const int res = 2;
  VolumeMesh m = distorted(type, res, 0.15, 2);
  std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
  for (int d = 0; d < 6; ++d) fixed[d] = 1;  // a few fixed DOFs to exercise the free-DOF map
  Assembled sys(m, make_material(name, {1.0, 10.0}), fixed);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = 1.1 * x[i] + n(rng);

  const FdErrors e = problem_fd_errors(sys.problem, x);
  EXPECT_LE(e.gradient, 1e-7) << name;
  EXPECT_LE(e.hessian, 1e-7) << name;
}

TEST_P(Assembly, ProjectedHessianIsPositiveSemidefinite) {
  const auto [type, name] = GetParam();
  const VolumeMesh m = distorted(type, 2, 0.1, 4);
  Assembled sys(m, make_material(name, {1.0, 10.0}), std::vector<std::uint8_t>(3 * m.vertex_count(), 0));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 0.3);  // large: some elements invert
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += n(rng);
  Eigen::VectorXd g;
  SparseLower H;
  const double E = sys.evaluate(x, g, &H, PsdProjection::clamp);
  if (!std::isfinite(E)) {  // some element inverted: only allowed for an energy undefined there, and reported as +inf
    EXPECT_EQ(E, std::numeric_limits<double>::infinity());
    EXPECT_FALSE(std::visit([](const auto& mat) { return std::decay_t<decltype(mat)>::inversion_safe; }, sys.elastic.material(0)));
    return;
  }
  const Eigen::MatrixXd Hfull = Eigen::MatrixXd(H).selfadjointView<Eigen::Lower>();
  const double lo = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hfull).eigenvalues().minCoeff();
  EXPECT_GE(lo, -1e-10 * Hfull.norm());
}

INSTANTIATE_TEST_SUITE_P(Elements, Assembly,
                         ::testing::Combine(::testing::Values(CellType::tet4, CellType::hex8),
                                            ::testing::Values("stable_neo_hookean", "stable_neo_hookean_log",
                                                              "neo_hookean", "corotated")),
                         [](const auto& info) {
                           return std::string(to_string(std::get<0>(info.param))) + "_" + std::get<1>(info.param);
                         });

/// Energy, gradient and Hessian at x with one thread and with two: expects them equal to the bit, and returns
/// the one-thread results.
std::tuple<double, Eigen::VectorXd, SparseLower> expect_same_for_one_and_two_threads(Assembled& sys, const Eigen::VectorXd& x) {
  Eigen::VectorXd g1, g2;
  SparseLower H1, H2;
  omp_set_num_threads(1);
  const double E1 = sys.evaluate(x, g1, &H1);
  omp_set_num_threads(2);
  const double E2 = sys.evaluate(x, g2, &H2);
  EXPECT_EQ(E1, E2);
  EXPECT_EQ(std::memcmp(g1.data(), g2.data(), sizeof(double) * g1.size()), 0);
  EXPECT_EQ(H1.nonZeros(), H2.nonZeros());
  if (H1.nonZeros() == H2.nonZeros()) {
    EXPECT_EQ(std::memcmp(H1.valuePtr(), H2.valuePtr(), sizeof(double) * H1.nonZeros()), 0);
  }
  return {E1, g1, H1};
}

TEST(Assembly, BitIdenticalForOneAndTwoThreads) {
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const int res = 6;
    const VolumeMesh m = distorted(type, res, 0.2, 6);
    Assembled sys(m, make_material("stable_neo_hookean", {1.0, 10.0}), boundary_fixed(res));
    sys.elastic.set_parallel_threshold(0);  // every loop in parallel, even on this small mesh
    EXPECT_GT(sys.elastic.colour_count(), 1);
    expect_same_for_one_and_two_threads(sys, flatten(m.vertices) * 1.2);
  }
}

TEST(Assembly, ScatterMapIsTheSameForOneAndTwoThreadsAndRefusesALayoutWithoutTheCells) {
  // 4 096 hexes: the scatter map's cells run in parallel. A layout of the diagonal alone lacks every cell's
  // couplings: a logic_error (after the parallel loop), for both thread counts.
  const VolumeMesh m = box_hexes(16);
  ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
  Stencil cells;
  elastic.stencil(flatten(m.vertices), cells);
  std::vector<int> numbering(3 * m.vertex_count());
  for (std::size_t d = 0; d < numbering.size(); ++d) numbering[d] = static_cast<int>(d);
  const HessianLayout layout(numbering, static_cast<int>(numbering.size()), {&cells});
  const HessianLayout diagonal(numbering, static_cast<int>(numbering.size()), {});
  const int threads = omp_get_max_threads();
  std::vector<int> maps[2];
  for (int t : {1, 2}) {
    omp_set_num_threads(t);
    maps[t - 1] = elastic.scatter_map(layout);
    EXPECT_THROW((void)elastic.scatter_map(diagonal), std::logic_error) << t << " threads";
  }
  omp_set_num_threads(threads);
  EXPECT_EQ(maps[0], maps[1]);
  // Written over an old map (a rebuilt layout reuses the term's): every entry, the −1s too.
  std::vector<int> over(maps[0].size(), 12345);
  elastic.scatter_map(layout, over);
  EXPECT_EQ(over, maps[0]);
  // Every entry mapped but the 3 · 8 · 7 / 2 upper halves of each cell's diagonal blocks (left at −1).
  EXPECT_EQ(std::count(maps[0].begin(), maps[0].end(), -1), 84 * m.cell_count());
}

TEST(Assembly, ChunksOfCellsGiveTheSameResultsForOneAndTwoThreads) {
  // Big enough for chunks (4 of 1024 cells at least): lattice-ordered cells make slabs, a few colours.
  for (const auto& [type, res] : {std::pair{CellType::hex8, 16}, std::pair{CellType::tet4, 10}}) {
    const VolumeMesh m = distorted(type, res, 0.2, 7);
    Assembled chunked(m, make_material("stable_neo_hookean", {1.0, 10.0}), boundary_fixed(res));
    Assembled cells(m, make_material("stable_neo_hookean", {1.0, 10.0}), boundary_fixed(res));
    EXPECT_EQ(chunked.elastic.chunk_cells(), 1024) << to_string(type);
    EXPECT_LE(chunked.elastic.colour_count(), ElasticTerm::kMaxChunkColours);
    cells.elastic.set_chunk_cells(0);
    EXPECT_EQ(cells.elastic.chunk_cells(), 1);
    EXPECT_GT(cells.elastic.colour_count(), chunked.elastic.colour_count());
    chunked.elastic.set_parallel_threshold(0);
    Eigen::VectorXd x = flatten(m.vertices) * 1.2;
    x[7] += 0.05;
    const auto [E1, g1, H1] = expect_same_for_one_and_two_threads(chunked, x);
    // The same sums in another order as the colouring of single cells.
    Eigen::VectorXd g_cells;
    SparseLower H_cells;
    const double E_cells = cells.evaluate(x, g_cells, &H_cells);
    EXPECT_NEAR(E1, E_cells, 1e-13 * std::abs(E_cells));
    EXPECT_LE((g1 - g_cells).norm(), 1e-13 * g_cells.norm());
    EXPECT_LE(SparseLower(H1 - H_cells).norm(), 1e-13 * H_cells.norm());
  }
  // Too few cells for four chunks: single cells.
  const VolumeMesh small = distorted(CellType::hex8, 6, 0.2, 8);
  EXPECT_EQ(ElasticTerm(small, make_material("stable_neo_hookean", {1.0, 10.0})).chunk_cells(), 1);
}

TEST(Assembly, HexStiffnessIsTheSumOverPointsOfBTransposedHB) {
  // The true Hessian of one distorted hex (the all-points kernel, add_hex_stiffness) against Σ_q w_q B_qᵀ H_q B_q
  // built densely, B_q the 9×24 map from the nodes' positions to vec F_q.
  for (const char* name : {"stable_neo_hookean", "stable_neo_hookean_log", "neo_hookean"}) {
    const VolumeMesh m = distorted(CellType::hex8, 1, 0.2, 9);
    const AnyMaterial mat = make_material(name, {1.0, 10.0});
    Assembled sys(m, mat, std::vector<std::uint8_t>(3 * m.vertex_count(), 0));
    Eigen::VectorXd x = flatten(m.vertices) * 1.1;
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += 0.03 * std::sin(3.0 * static_cast<double>(i));
    Eigen::VectorXd g;
    SparseLower H;
    sys.evaluate(x, g, &H, PsdProjection::none);
    const Eigen::MatrixXd got = Eigen::MatrixXd(H).selfadjointView<Eigen::Lower>();
    const HexRest r = std::get<std::vector<HexRest>>(sys.elastic.rest())[0];
    Eigen::Matrix<double, 3, 8> X;
    for (int a = 0; a < 8; ++a) X.col(a) = x.segment<3>(3 * m.cells(a, 0));
    Eigen::MatrixXd want = Eigen::MatrixXd::Zero(24, 24);
    for (int q = 0; q < 8; ++q) {
      const Mat3 F = X * r.G[q];
      Eigen::Matrix<double, 9, 24> B = Eigen::Matrix<double, 9, 24>::Zero();
      for (int a = 0; a < 8; ++a)
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) B(3 * j + i, 3 * a + i) = r.G[q](a, j);  // vec F column-major
      const Mat9 Hq = std::visit([&](const auto& mm) { return mm.hessian(F); }, mat);
      want += r.weight[q] * B.transpose() * Hq * B;
    }
    // The mesh's vertex order is the cell's (one cell): DOF 3a+i is vertex cells(a, 0), coordinate i.
    Eigen::MatrixXd want_by_vertex(24, 24);
    for (int a = 0; a < 8; ++a)
      for (int b = 0; b < 8; ++b)
        want_by_vertex.block<3, 3>(3 * m.cells(a, 0), 3 * m.cells(b, 0)) = want.block<3, 3>(3 * a, 3 * b);
    EXPECT_LE((got - want_by_vertex).norm(), 1e-12 * want.norm()) << name;
  }
}

TEST(Assembly, RejectsDegenerateAndBadInput) {
  const AnyMaterial snh = make_material("stable_neo_hookean", {1, 10});
  VolumeMesh m = box_tets(1);
  m.vertices.col(m.cells(1, 0)) = m.vertices.col(m.cells(0, 0));  // collapse tet 0
  EXPECT_THROW(ElasticTerm(m, snh), DegenerateElement);
  VolumeMesh bad_index = box_tets(1);
  bad_index.cells(2, 3) = 999;  // checked before the rest state reads vertex 999
  EXPECT_THROW(ElasticTerm(bad_index, snh), std::invalid_argument);
  VolumeMesh repeated = box_tets(1);
  repeated.cells(3, 2) = repeated.cells(0, 2);  // a vertex twice in one cell: refused before the rest state
  try {
    ElasticTerm term(repeated, snh);
    FAIL() << "a cell with a vertex twice must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "cell 2: vertex " + std::to_string(repeated.cells(0, 2)) + " appears twice");
  }
  const VolumeMesh ok = box_tets(1);
  EXPECT_THROW(ElasticTerm(ok, {snh, snh}, {}), std::invalid_argument) << "two materials need an index per cell";
  EXPECT_THROW(ElasticTerm(ok, {snh, snh}, {0, 1, 2, 0, 0, 0}), std::invalid_argument) << "index out of range";
  EXPECT_THROW(ElasticTerm(ok, {snh}, {0, 0}), std::invalid_argument) << "one index per cell";
  EXPECT_THROW(ElasticTerm(ok, {snh}, {}, Eigen::VectorXd::Ones(5)), std::invalid_argument) << "one scale per cell";
  Eigen::VectorXd zero = Eigen::VectorXd::Ones(6);
  zero[2] = 0.0;
  EXPECT_THROW(ElasticTerm(ok, {snh}, {}, zero), std::invalid_argument) << "scales must be > 0";
}

/// A deformed state of the mesh: an affine map plus a small random perturbation.
Eigen::VectorXd deformed(const VolumeMesh& m, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 0.03);
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = (i % 3 == 1 ? 1.3 : 0.9) * x[i] + n(rng);
  return x;
}

TEST(Assembly, PerCellMaterialsAreEachCellsOwn) {
  // Two materials (every third cell the second): the energy and gradient are the sums of two
  // one-material terms over the cells of each, on the same vertices.
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const VolumeMesh m = distorted(type, 2, 0.1, 11);
    const AnyMaterial soft = make_material("stable_neo_hookean", {1.0, 10.0});
    const AnyMaterial hard = make_material("corotated", {5.0, 20.0});
    std::vector<int> which(m.cell_count());
    VolumeMesh a = m, b = m;
    std::vector<int> in_a, in_b;
    for (Eigen::Index c = 0; c < m.cell_count(); ++c) (c % 3 == 0 ? in_b : in_a).push_back(static_cast<int>(c));
    for (int c : in_b) which[c] = 1;
    a.cells = m.cells(Eigen::all, in_a);
    b.cells = m.cells(Eigen::all, in_b);
    ElasticTerm mixed(m, {soft, hard}, which), only_a(a, soft), only_b(b, hard);
    const Eigen::VectorXd x = deformed(m, 12);
    EXPECT_NEAR(mixed.energy(x), only_a.energy(x) + only_b.energy(x), 1e-12 * std::abs(mixed.energy(x)));
    Eigen::VectorXd g_mixed = Eigen::VectorXd::Zero(x.size()), g_sum = g_mixed;
    mixed.evaluate(x, &g_mixed, nullptr, PsdProjection::clamp);
    only_a.evaluate(x, &g_sum, nullptr, PsdProjection::clamp);
    only_b.evaluate(x, &g_sum, nullptr, PsdProjection::clamp);
    EXPECT_LE((g_mixed - g_sum).norm(), 1e-12 * g_sum.norm());
    const ElasticTerm::Deformation d = mixed.deformation(x), d_b = only_b.deformation(x);
    for (std::size_t k = 0; k < in_b.size(); ++k) EXPECT_EQ(d.energy_density[in_b[k]], d_b.energy_density[k]);
    EXPECT_EQ(name_of(mixed.material(in_b.front())), "corotated");
    EXPECT_EQ(name_of(mixed.material(in_a.front())), "stable_neo_hookean");
  }
}

TEST(Assembly, WeightScalesScaleEachCellsEnergy) {
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const VolumeMesh m = distorted(type, 2, 0.1, 13);
    const AnyMaterial mat = make_material("stable_neo_hookean", {1.0, 10.0});
    Eigen::VectorXd scale(m.cell_count());
    for (Eigen::Index c = 0; c < m.cell_count(); ++c) scale[c] = 0.25 + 0.5 * static_cast<double>(c % 3);
    ElasticTerm plain(m, mat), scaled(m, {mat}, {}, scale);
    const Eigen::VectorXd x = deformed(m, 14);
    // Per cell: a term over that cell alone, times its scale.
    double expected = 0.0;
    for (Eigen::Index c = 0; c < m.cell_count(); ++c) {
      VolumeMesh one = m;
      one.cells = m.cells.col(c);
      expected += scale[c] * ElasticTerm(one, mat).energy(x);
    }
    EXPECT_NEAR(scaled.energy(x), expected, 1e-12 * std::abs(expected));
    EXPECT_NEAR(rest_volumes(scaled.rest()).sum(), rest_volumes(plain.rest()).dot(scale), 1e-12);
    const ElasticTerm::Deformation dp = plain.deformation(x), ds = scaled.deformation(x);
    EXPECT_LE((dp.energy_density - ds.energy_density).cwiseAbs().maxCoeff(), 1e-12) << "a density is per volume";
  }
}

// Congruent cells (a lattice's, equal but for the rounding of their coordinates) share one rest record; the
// energy, gradient and Hessian are those of a record per cell to rounding; distorted or rescaled cells keep
// their own records.
TEST(ElasticTermRest, CongruentCellsShareARecordAndGiveTheSameResults) {
  for (const CellType type : {CellType::hex8, CellType::tet4}) {
    const int res = 4;
    const VolumeMesh m = distorted(type, res, 0.0, 1);
    const AnyMaterial mat = make_material("stable_neo_hookean", {1.0, 10.0});
    Assembled shared(m, mat, boundary_fixed(res)), own(m, mat, boundary_fixed(res));
    own.elastic.share_rest(false);
    EXPECT_EQ(own.elastic.rest_records(), m.cell_count());
    EXPECT_LE(shared.elastic.rest_records(), type == CellType::hex8 ? 2 : 12) << to_string(type);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-0.1, 0.1);
    Eigen::VectorXd x = flatten(m.vertices);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += u(rng);
    Eigen::VectorXd g_shared, g_own;
    SparseLower H_shared, H_own;
    const double E_shared = shared.evaluate(x, g_shared, &H_shared), E_own = own.evaluate(x, g_own, &H_own);
    EXPECT_NEAR(E_shared, E_own, 1e-12 * std::abs(E_own));
    EXPECT_LE((g_shared - g_own).norm(), 1e-12 * g_own.norm());
    EXPECT_LE(SparseLower(H_shared - H_own).norm(), 1e-12 * H_own.norm());
    EXPECT_LE((shared.elastic.rest_volumes() - own.elastic.rest_volumes()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_EQ(rest_volumes(shared.elastic.rest()).size(), m.cell_count());
    // Sharing again after a record per cell gives the same records.
    own.elastic.share_rest(true);
    EXPECT_EQ(own.elastic.rest_records(), shared.elastic.rest_records());
  }
  // Distorted cells: none alike. One cell's weight scaled: it alone leaves the shared record.
  const VolumeMesh bent = distorted(CellType::hex8, 3, 0.2, 4);
  EXPECT_EQ(ElasticTerm(bent, make_material("stable_neo_hookean", {1.0, 10.0})).rest_records(), bent.cell_count());
  const VolumeMesh box = distorted(CellType::hex8, 3, 0.0, 4);
  Eigen::VectorXd scale = Eigen::VectorXd::Ones(box.cell_count());
  scale[5] = 1.0 + 1e-9;
  const ElasticTerm plain(box, make_material("stable_neo_hookean", {1.0, 10.0}));
  const ElasticTerm one_scaled(box, {make_material("stable_neo_hookean", {1.0, 10.0})}, {}, scale);
  EXPECT_EQ(one_scaled.rest_records(), plain.rest_records() + 1);
  EXPECT_DOUBLE_EQ(one_scaled.rest_volumes()[5], plain.rest_volumes()[5] * scale[5]);
}

}  // namespace
}  // namespace snh
