// Assembly: patch test, finite differences of the assembled gradient and Hessian on distorted meshes,
// the sparse pattern, and bit-identical results for 1 and 2 threads.
#include <gtest/gtest.h>

#include <omp.h>

#include <random>

#include "snh/fem/elastic_system.hpp"
#include "snh/mesh/box.hpp"

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

Eigen::VectorXd flatten(const Eigen::Matrix3Xd& V) { return Eigen::Map<const Eigen::VectorXd>(V.data(), V.size()); }

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

class Assembly : public ::testing::TestWithParam<std::tuple<CellType, std::string>> {};

TEST_P(Assembly, PatchTestAffineDeformationIsAnEquilibrium) {
  const auto [type, name] = GetParam();
  const int res = 3;
  const VolumeMesh m = distorted(type, res, 0.2, 1);
  const ElasticSystem sys(m, make_material(name, {1.0, 10.0}), boundary_fixed(res));
  Mat3 A;
  A << 1.3, 0.2, -0.1, 0.05, 0.8, 0.3, -0.2, 0.1, 1.1;
  const Eigen::Matrix3Xd X = (A * m.vertices).colwise() + Eigen::Vector3d(0.3, -0.2, 0.5);
  Eigen::VectorXd g;
  const double E = sys.evaluate(flatten(X), g, nullptr);
  ASSERT_GT(sys.free_count(), 0);
  // Energy = rest volume × ψ(A); interior forces vanish.
  const double psi = std::visit([&](const auto& mat) { return mat.psi(A); }, sys.material());
  const double volume = rest_volumes(sys.rest()).sum();
  EXPECT_NEAR(E, volume * psi, 1e-12 * std::abs(volume * psi));
  const double scale = std::visit([&](const auto& mat) { return mat.pk1(A).norm(); }, sys.material());
  EXPECT_LE(g.norm(), 1e-12 * scale) << name;
}

TEST_P(Assembly, GradientAndHessianMatchFiniteDifferences) {
  const auto [type, name] = GetParam();
  const int res = 2;
  VolumeMesh m = distorted(type, res, 0.15, 2);
  std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
  for (int d = 0; d < 6; ++d) fixed[d] = 1;  // a few fixed DOFs to exercise the free-DOF map
  const ElasticSystem sys(m, make_material(name, {1.0, 10.0}), fixed);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = 1.1 * x[i] + n(rng);

  Eigen::VectorXd g;
  SparseLower H;
  sys.evaluate(x, g, &H, PsdProjection::none);
  const Eigen::MatrixXd Hfull = Eigen::MatrixXd(H).selfadjointView<Eigen::Lower>();

  double best_g = 1e300, best_H = 1e300;
  for (double eps : {1e-3, 1e-4, 1e-5, 1e-6}) {
    Eigen::VectorXd fd_g(sys.free_count());
    Eigen::MatrixXd fd_H(sys.free_count(), sys.free_count());
    for (Eigen::Index d = 0, f = 0; d < x.size(); ++d) {
      if (fixed[d]) continue;
      Eigen::VectorXd xp = x, xm = x, gp, gm;
      xp[d] += eps;
      xm[d] -= eps;
      fd_g[f] = (sys.energy(xp) - sys.energy(xm)) / (2 * eps);
      sys.evaluate(xp, gp, nullptr);
      sys.evaluate(xm, gm, nullptr);
      fd_H.col(f) = (gp - gm) / (2 * eps);
      ++f;
    }
    best_g = std::min(best_g, (fd_g - g).norm() / g.norm());
    best_H = std::min(best_H, (fd_H - Hfull).norm() / Hfull.norm());
  }
  EXPECT_LE(best_g, 1e-7) << name;
  EXPECT_LE(best_H, 1e-7) << name;
}

TEST_P(Assembly, ProjectedHessianIsPositiveSemidefinite) {
  const auto [type, name] = GetParam();
  const VolumeMesh m = distorted(type, 2, 0.1, 4);
  const ElasticSystem sys(m, make_material(name, {1.0, 10.0}), std::vector<std::uint8_t>(3 * m.vertex_count(), 0));
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 0.3);  // large: some elements invert
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += n(rng);
  Eigen::VectorXd g;
  SparseLower H;
  const double E = sys.evaluate(x, g, &H, PsdProjection::clamp);
  if (!std::isfinite(E)) {  // some element inverted: only allowed for an energy undefined there, and reported as +inf
    EXPECT_EQ(E, std::numeric_limits<double>::infinity());
    EXPECT_FALSE(std::visit([](const auto& mat) { return std::decay_t<decltype(mat)>::inversion_safe; }, sys.material()));
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

TEST(Assembly, BitIdenticalForOneAndTwoThreads) {
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    const int res = 6;
    const VolumeMesh m = distorted(type, res, 0.2, 6);
    ElasticSystem sys(m, make_material("stable_neo_hookean", {1.0, 10.0}), boundary_fixed(res));
    sys.set_parallel_threshold(0);  // every loop in parallel, even on this small mesh
    EXPECT_GT(sys.colour_count(), 1);
    Eigen::VectorXd x = flatten(m.vertices) * 1.2;
    Eigen::VectorXd g1, g2;
    SparseLower H1, H2;
    omp_set_num_threads(1);
    const double E1 = sys.evaluate(x, g1, &H1);
    omp_set_num_threads(2);
    const double E2 = sys.evaluate(x, g2, &H2);
    EXPECT_EQ(E1, E2);
    EXPECT_EQ(std::memcmp(g1.data(), g2.data(), sizeof(double) * g1.size()), 0);
    ASSERT_EQ(H1.nonZeros(), H2.nonZeros());
    EXPECT_EQ(std::memcmp(H1.valuePtr(), H2.valuePtr(), sizeof(double) * H1.nonZeros()), 0);
  }
}

TEST(Assembly, RejectsDegenerateAndBadInput) {
  VolumeMesh m = box_tets(1);
  m.vertices.col(m.cells(1, 0)) = m.vertices.col(m.cells(0, 0));  // collapse tet 0
  EXPECT_THROW(ElasticSystem(m, make_material("stable_neo_hookean", {1, 10}), std::vector<std::uint8_t>(24, 0)),
               DegenerateElement);
  EXPECT_THROW(ElasticSystem(box_tets(1), make_material("stable_neo_hookean", {1, 10}), std::vector<std::uint8_t>(5, 0)),
               std::invalid_argument);
  VolumeMesh bad_index = box_tets(1);
  bad_index.cells(2, 3) = 999;  // checked before the rest state reads vertex 999
  EXPECT_THROW(ElasticSystem(bad_index, make_material("stable_neo_hookean", {1, 10}), std::vector<std::uint8_t>(24, 0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace snh
