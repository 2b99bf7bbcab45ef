// Muscle cells of an ElasticTerm (set_fibres): the energy, gradient and Hessian against finite differences; a
// free muscle (its faces only held in their own planes) contracts to exactly the shape of its active strain,
// its fibres at 1 − α and its volume kept, on hexes and tets; a muscle clamped at both ends pulls on them
// harder as its activation grows; and the cells without fibres are left as they were.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/newton.hpp"
#include "fem/problem_fd.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::flatten;

CellFibre fibre_along(const Vec3& a, double alpha, double k = 1.0) {
  CellFibre f;
  f.direction = a.normalized();
  f.energy = {FibreModel::signed_arap, k};
  f.active = ActiveStrain::along(a, alpha);
  return f;
}

/// Flags of the DOFs to hold: coordinate k of every vertex where `where(vertex, k)`.
template <class Where>
std::vector<std::uint8_t> held(const VolumeMesh& m, Where where) {
  std::vector<std::uint8_t> flags(3 * static_cast<std::size_t>(m.vertex_count()), 0);
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    for (int k = 0; k < 3; ++k) flags[static_cast<std::size_t>(3 * v + k)] = where(Vec3(m.vertices.col(v)), k) ? 1 : 0;
  return flags;
}

NewtonReport solve(ElasticTerm& elastic, const std::vector<std::uint8_t>& flags, Eigen::VectorXd& x) {
  Problem problem{DofMap(flags)};
  problem.add(elastic);
  auto solver = make_linear_solver({.name = "ldlt"});
  return newton_solve(problem, x, *solver, {.max_iterations = 100, .tolerance = 1e-11});
}

TEST(MuscleCells, EnergyGradientAndHessianMatchFiniteDifferences) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  for (const bool hexes : {true, false}) {
    const VolumeMesh m = hexes ? box_hexes(2) : box_tets(2);
    ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
    // Half the cells a muscle along (1, 2, 2)/3 contracted by 0.2, a quarter along z by 0.4, the rest passive.
    std::vector<int> of(static_cast<std::size_t>(m.cell_count()), -1);
    for (std::size_t c = 0; c < of.size(); ++c) of[c] = c % 4 == 0 ? -1 : c % 4 == 1 ? 1 : 0;
    elastic.set_fibres(of, {fibre_along(Vec3(1, 2, 2), 0.2, 3.0), fibre_along(Vec3::UnitZ(), 0.4, 0.5)});
    Problem problem{DofMap(std::vector<std::uint8_t>(3 * static_cast<std::size_t>(m.vertex_count()), 0))};
    problem.add(elastic);
    Eigen::VectorXd x = flatten(m.vertices);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += u(rng);
    const FdErrors e = problem_fd_errors(problem, x);
    EXPECT_LE(e.gradient, 1e-6) << (hexes ? "hexes" : "tets");
    EXPECT_LE(e.hessian, 1e-6) << (hexes ? "hexes" : "tets");
  }
}

TEST(MuscleCells, AFreeMuscleContractsExactlyToItsActiveShape) {
  // A cube of muscle along x, each face x = −1, y = −1, z = −1 held in its own plane only (it may slide in
  // it): with activation α the rest is x ↦ −1 + (1 − α)(x + 1) along the fibres and (1 − α)^(−1/2) across,
  // homogeneous, so every vertex is there to the Newton tolerance, and the volume is kept.
  for (const bool hexes : {true, false}) {
    for (const double alpha : {0.15, 0.4}) {
      const VolumeMesh m = hexes ? box_hexes(3) : box_tets(3);
      ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
      elastic.set_fibres(std::vector<int>(static_cast<std::size_t>(m.cell_count()), 0), {fibre_along(Vec3::UnitX(), alpha)});
      Eigen::VectorXd x = flatten(m.vertices);
      const NewtonReport r = solve(elastic, held(m, [](const Vec3& p, int k) { return p[k] == -1.0; }), x);
      ASSERT_TRUE(r.converged) << (hexes ? "hexes" : "tets") << " alpha " << alpha;
      const double across = 1.0 / std::sqrt(1.0 - alpha);
      double worst = 0.0;
      for (Eigen::Index v = 0; v < m.vertex_count(); ++v) {
        const Vec3 X = m.vertices.col(v);
        const Vec3 want(-1.0 + (1.0 - alpha) * (X.x() + 1.0), -1.0 + across * (X.y() + 1.0), -1.0 + across * (X.z() + 1.0));
        worst = std::max(worst, (x.segment<3>(3 * v) - want).norm());
      }
      EXPECT_LE(worst, 1e-9) << (hexes ? "hexes" : "tets") << " alpha " << alpha;
      EXPECT_NEAR(elastic.deformation(x).volume, 8.0, 1e-8) << (hexes ? "hexes" : "tets") << " alpha " << alpha;
      EXPECT_NEAR(elastic.energy(x), 0.0, 1e-12) << (hexes ? "hexes" : "tets") << " alpha " << alpha;
    }
  }
}

TEST(MuscleCells, AClampedMusclePullsHarderAsItsActivationGrows) {
  // Both ends held: the muscle cannot shorten, so it pulls on the end x = 1 along −x, the more the higher
  // the activation (the sum of the energy's gradient over that face's x DOFs is the force it exerts there).
  const VolumeMesh m = box_hexes(3);
  double previous = 0.0;
  for (const double alpha : {0.0, 0.05, 0.1, 0.2, 0.3}) {
    ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
    elastic.set_fibres(std::vector<int>(static_cast<std::size_t>(m.cell_count()), 0), {fibre_along(Vec3::UnitX(), alpha, 2.0)});
    Eigen::VectorXd x = flatten(m.vertices);
    ASSERT_TRUE(solve(elastic, held(m, [](const Vec3& p, int) { return std::abs(p.x()) == 1.0; }), x).converged) << alpha;
    Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
    (void)elastic.evaluate(x, &g, nullptr, PsdProjection::none);
    double pull = 0.0;  // the force on the end's holder: −Σ ∂E/∂x over the face, positive when pulled inwards
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      if (m.vertices(0, v) == 1.0) pull += g[3 * v];
    if (alpha == 0.0) {
      EXPECT_NEAR(pull, 0.0, 1e-12);
    }
    else EXPECT_GT(pull, previous + 1e-3) << "alpha " << alpha;
    previous = pull;
  }
}

TEST(MuscleCells, BadFibresAreRefused) {
  const VolumeMesh m = box_hexes(1);
  ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
  EXPECT_THROW(elastic.set_fibres({0, 0}, {fibre_along(Vec3::UnitX(), 0.1)}), std::invalid_argument);  // 2 cells for 1
  EXPECT_THROW(elastic.set_fibres({1}, {fibre_along(Vec3::UnitX(), 0.1)}), std::invalid_argument);
  CellFibre bent = fibre_along(Vec3::UnitX(), 0.1);
  bent.direction = Vec3(1, 1, 0);
  EXPECT_THROW(elastic.set_fibres({0}, {bent}), std::invalid_argument);
  EXPECT_THROW(elastic.set_active_strain(0, ActiveStrain{}), std::invalid_argument);  // no fibres yet
  elastic.set_fibres({0}, {fibre_along(Vec3::UnitX(), 0.1)});
  elastic.set_active_strain(0, ActiveStrain::along(Vec3::UnitX(), 0.3));
  EXPECT_NEAR(elastic.fibres()[0].active.deformation()(0, 0), 0.7, 1e-15);
}

}  // namespace
}  // namespace snh
