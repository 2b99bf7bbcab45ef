// Multigrid (issue 15). Geometric (mg): lattice coordinates from the cells, the V-cycle is symmetric and
// positive definite, conjugate gradients with it converge in few iterations on hex elasticity with pins
// (whole lattices and partial ones), and the solver refuses meshes that are not lattices. Algebraic (amg,
// smoothed aggregation): the same V-cycle properties on tets, iterations that stay flat as the mesh is
// refined, whole runs that match CHOLMOD and do not depend on the thread count.
#include <gtest/gtest.h>
#include <omp.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "setup/limb_model.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/mesh/box.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/setup/stretch.hpp"
#include "snh/solve/multigrid.hpp"
#include "snh/solve/newton.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

/// The cells of `mesh` for which keep(cell) holds, with only the vertices they use (renumbered in order).
VolumeMesh keep_cells(const VolumeMesh& mesh, const std::function<bool(Eigen::Index)>& keep) {
  std::vector<int> cells, renumber(mesh.vertex_count(), -1);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    if (keep(c)) cells.push_back(static_cast<int>(c));
  std::vector<int> used;
  for (int c : cells)
    for (int k = 0; k < 8; ++k) used.push_back(mesh.cells(k, c));
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  VolumeMesh out;
  out.type = CellType::hex8;
  out.vertices.resize(3, static_cast<Eigen::Index>(used.size()));
  for (std::size_t i = 0; i < used.size(); ++i) {
    renumber[used[i]] = static_cast<int>(i);
    out.vertices.col(static_cast<Eigen::Index>(i)) = mesh.vertices.col(used[i]);
  }
  out.cells.resize(8, static_cast<Eigen::Index>(cells.size()));
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (int k = 0; k < 8; ++k) out.cells(k, static_cast<Eigen::Index>(c)) = renumber[mesh.cells(k, cells[c])];
  return out;
}

/// A Stable Neo-Hookean (ν = 0.45) Hessian of `mesh` at a random deformation near rest, PSD-projected, on the
/// DOFs that `kinematic` leaves free.
struct System {
  System(const VolumeMesh& mesh, const std::vector<std::uint8_t>& kinematic, unsigned seed)
      : elastic(mesh, make_material("stable_neo_hookean", Lame{1.0, 9.0})), problem(DofMap(kinematic)) {
    problem.add(elastic);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size());
    const double h = (mesh.vertices.col(mesh.cells(1, 0)) - mesh.vertices.col(mesh.cells(0, 0))).norm();
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += 0.1 * h * u(rng);
    Eigen::VectorXd g;
    problem.evaluate(x, g, &H, PsdProjection::clamp);
  }
  ElasticTerm elastic;
  Problem problem;
  HessianMatrix H;
};

/// DOFs of the vertices with y at its minimum, all three axes; and the x DOF of those with y at its maximum.
std::vector<std::uint8_t> pins(const VolumeMesh& mesh) {
  std::vector<std::uint8_t> k(3 * mesh.vertex_count(), 0);
  const double lo = mesh.vertices.row(1).minCoeff(), hi = mesh.vertices.row(1).maxCoeff();
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    if (mesh.vertices(1, v) == lo) k[3 * v] = k[3 * v + 1] = k[3 * v + 2] = 1;
    if (mesh.vertices(1, v) == hi) k[3 * v] = 1;
  }
  return k;
}

int iterations_with(const SparseLower& A, const Preconditioner& M, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const CgResult r = conjugate_gradients(A, b, M, 1e-10 * b.norm(), 5000, x);
  EXPECT_EQ(r.status, CgStatus::converged);
  return r.iterations;
}

TEST(LatticeCoordinates, AreTheBoxIndices) {
  const int res = 3;
  const LatticeCoordinates l = lattice_coordinates(box_hexes(res));
  for (int k = 0; k <= res; ++k)
    for (int j = 0; j <= res; ++j)
      for (int i = 0; i <= res; ++i) EXPECT_EQ(l.coordinates.col(lattice_index(res, i, j, k)), Eigen::Vector3i(i, j, k));
  for (int p : l.piece) EXPECT_EQ(p, 0);
}

TEST(LatticeCoordinates, MeshesThatAreNotLatticesAreRefused) {
  EXPECT_THROW((void)lattice_coordinates(box_tets(2)), std::invalid_argument);
  VolumeMesh m = box_hexes(2);
  std::swap(m.cells(1, 3), m.cells(2, 3));  // cell 3 mirrored: its x and y disagree with its neighbours'
  try {
    (void)lattice_coordinates(m);
    FAIL() << "a cell that contradicts its neighbours must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cell 3"), std::string::npos) << e.what();
  }
  const std::vector<int> free(3 * box_tets(2).vertex_count(), 0);
  const VolumeMesh tets = box_tets(2);
  EXPECT_THROW((void)make_linear_solver({.name = "mg"}, {.mesh = &tets, .free_index = &free}), std::invalid_argument);
  EXPECT_THROW((void)make_linear_solver({.name = "mg"}), std::invalid_argument) << "no mesh behind the matrix";
}

/// xᵀ M y = yᵀ M x and xᵀ M x > 0 on random vectors; PCG with the V-cycle converges in a fraction of Jacobi's
/// iterations, to the same solution.
/// Returns the V-cycle's CG iterations.
int check_vcycle(const VolumeMesh& mesh, int levels_at_least, int max_iterations, Coarsening how = Coarsening::lattice) {
  const std::vector<std::uint8_t> kinematic = pins(mesh);
  System s(mesh, kinematic, 7);
  const SparseLower& A = s.H.matrix;
  MultigridPreconditioner M(mesh, s.problem.dofs().free_index(), how);
  if (!M.compute(A)) {
    ADD_FAILURE() << "the V-cycle found a positive definite matrix not positive definite";
    return 0;
  }
  EXPECT_GE(M.levels(), levels_at_least);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n;
  const Eigen::Index size = A.rows();
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x(size), y(size), Mx, My;
    for (Eigen::Index i = 0; i < size; ++i) x[i] = n(rng), y[i] = n(rng);
    M.apply(x, Mx);
    M.apply(y, My);
    EXPECT_NEAR(y.dot(Mx), x.dot(My), 1e-12 * Mx.norm() * y.norm());
    EXPECT_GT(x.dot(Mx), 0.0);
  }
  Eigen::VectorXd b(size);
  for (Eigen::Index i = 0; i < size; ++i) b[i] = n(rng);
  Eigen::VectorXd x_mg, x_jacobi;
  const int mg = iterations_with(A, M, b, x_mg), jacobi = iterations_with(A, JacobiPreconditioner(A), b, x_jacobi);
  std::cout << mesh.cell_count() << " " << to_string(mesh.type) << " cells, " << M.levels() << " levels: V-cycle " << mg
            << ", Jacobi " << jacobi << " CG iterations\n";
  EXPECT_LE(mg, max_iterations);
  EXPECT_LT(5 * mg, jacobi);
  EXPECT_LE((x_mg - x_jacobi).norm(), 1e-7 * x_jacobi.norm());
  return mg;
}

TEST(Multigrid, VCycleIsSymmetricPositiveAndConvergesFastOnAPinnedBox) { check_vcycle(box_hexes(16), 2, 30); }

// The smoother keeps its rows in half precision (largest value 65 504, smallest normal 6·10⁻⁵), each node's
// row scaled by a power of two so that its entries are at most 1. The same matrix times 10⁻³⁰ … 10³⁰ (a
// material's units, a contact barrier's stiffness) must then be smoothed as well as the unit one: unscaled,
// 10⁸ times this box's entries overflow half precision, and 10⁻⁸ times them vanish.
TEST(Multigrid, TheSmootherHoldsAMatrixOfAnyMagnitude) {
  const VolumeMesh mesh = box_hexes(12);
  System s(mesh, pins(mesh), 7);
  const SparseLower& A = s.H.matrix;
  MultigridPreconditioner M(mesh, s.problem.dofs().free_index());
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n;
  Eigen::VectorXd b(A.rows());
  for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = n(rng);
  ASSERT_TRUE(M.compute(A));
  Eigen::VectorXd x;
  const int unit = iterations_with(A, M, b, x);
  for (const double c : {1e-30, 1e-8, 1e8, 1e30}) {
    const SparseLower cA = c * A;
    ASSERT_TRUE(M.compute(cA)) << c;
    Eigen::VectorXd y;
    const int scaled = iterations_with(cA, M, b, y);
    EXPECT_LE(std::abs(scaled - unit), 1) << "the matrix times " << c << ": " << scaled << " CG iterations, " << unit << " for it unscaled";
    EXPECT_LE((c * y - x).norm(), 1e-8 * x.norm()) << c;
  }
}

/// A box of 20³ hexes less a tunnel along y, a cavity, and a slab along z that splits it into two pieces.
VolumeMesh partial_lattice() {
  const int res = 20;
  return keep_cells(box_hexes(res), [&](Eigen::Index c) {
    const int i = static_cast<int>(c % res), j = static_cast<int>(c / res % res), k = static_cast<int>(c / (res * res));
    const bool tunnel = i >= 3 && i < 6 && k >= 4 && k < 9;
    const bool cavity = i >= 10 && i < 15 && j >= 7 && j < 12 && k >= 11 && k < 16;
    const bool slab = k == 17;
    return !tunnel && !cavity && !slab;
  });
}

TEST(Multigrid, APartialLatticeWithHolesAndTwoPiecesWorks) {
  const VolumeMesh mesh = partial_lattice();
  check_vcycle(mesh, 2, 40);
  const std::vector<int> piece = lattice_coordinates(mesh).piece;
  EXPECT_EQ(*std::max_element(piece.begin(), piece.end()), 1) << "two pieces";
}

// Smoothed aggregation on tets (any mesh: no lattice needed), pinned as above; the coarse levels are made
// from the matrix, so a tet box of 12³ cells (6 591 free DOFs) has three levels.
TEST(AlgebraicMultigrid, VCycleIsSymmetricPositiveAndConvergesFastOnAPinnedTetBox) {
  check_vcycle(box_tets(12), 3, 40, Coarsening::aggregation);
}

// The iterations stay about flat as the mesh is refined (h-independence): res 6 to 18, 1 029 to 20 577 free DOFs.
TEST(AlgebraicMultigrid, IterationsStayFlatAsTheTetMeshIsRefined) {
  std::vector<int> its;
  for (int res : {6, 12, 18}) its.push_back(check_vcycle(box_tets(res), 2, 45, Coarsening::aggregation));
  EXPECT_LE(its.back(), 2 * its.front()) << "res 18 against res 6";
}

TEST(AlgebraicMultigrid, WorksOnAPartialHexLatticeWithHolesAndTwoPiecesToo) {
  check_vcycle(partial_lattice(), 3, 40, Coarsening::aggregation);
}

/// The smoother's colouring is valid on every level (no two coupled nodes share a colour; lattices: the 8
/// parities), and the V-cycle (built and applied) and the product are bit-identical with 1 and 2 threads,
/// every level run in parallel.
void check_threads(const VolumeMesh& mesh, Coarsening how) {
  System s(mesh, pins(mesh), 11);
  const SparseLower& A = s.H.matrix;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n;
  Eigen::VectorXd r(A.rows());
  for (Eigen::Index i = 0; i < A.rows(); ++i) r[i] = n(rng);
  const int threads = omp_get_max_threads();
  Eigen::VectorXd z[2], y[2];
  for (int t : {1, 2}) {
    omp_set_num_threads(t);
    MultigridPreconditioner M(mesh, s.problem.dofs().free_index(), how);
    M.set_parallel_nodes(1);
    ASSERT_TRUE(M.compute(A));
    ASSERT_GE(M.levels(), 2);
    M.apply(r, z[t - 1]);
    M.multiply(r, y[t - 1]);
    if (t == 2) continue;
    for (int l = 0; l < M.levels(); ++l) {
      const std::vector<int>& colour = M.colours(l);
      const auto pairs = M.couplings(l);
      EXPECT_FALSE(pairs.empty()) << "level " << l;
      int clashes = 0;
      for (const auto& [i, j] : pairs) clashes += colour[i] == colour[j];
      EXPECT_EQ(clashes, 0) << "level " << l << ": coupled nodes of one colour";
      const int colours = *std::max_element(colour.begin(), colour.end()) + 1;
      std::cout << "level " << l << ": " << colour.size() << " nodes, " << colours << " colours\n";
      if (how == Coarsening::lattice) {
        EXPECT_LE(colours, 8) << "level " << l;
      }
    }
  }
  omp_set_num_threads(threads);
  ASSERT_EQ(z[0].size(), z[1].size());
  EXPECT_EQ(std::memcmp(z[0].data(), z[1].data(), sizeof(double) * z[0].size()), 0) << "V-cycle";
  EXPECT_EQ(std::memcmp(y[0].data(), y[1].data(), sizeof(double) * y[0].size()), 0) << "product";
  EXPECT_LE((y[0] - (A.selfadjointView<Eigen::Lower>() * r)).norm(), 1e-12 * y[0].norm()) << "the product is A r";
}

TEST(Multigrid, ColouredSmootherIsValidAndTheSameForOneAndTwoThreads) { check_threads(partial_lattice(), Coarsening::lattice); }

TEST(AlgebraicMultigrid, ColouredSmootherIsValidAndTheSameForOneAndTwoThreads) {
  check_threads(box_tets(12), Coarsening::aggregation);
}

TEST(Multigrid, AContactCouplingMovesOnlyItsOwnNodeOutOfTheParityColours) {
  // A spring block between two free nodes of one parity, four cells apart (what a contact pair adds to the
  // pattern), on a pinned box: on the finest level only the higher of the two leaves the 8 parity colours;
  // every other node keeps its parity, every level's colouring stays valid, and CG converges in about the
  // iterations of the box without the spring.
  const int res = 16;
  const VolumeMesh mesh = box_hexes(res);
  System s(mesh, pins(mesh), 13);
  const std::vector<int>& row = s.problem.dofs().free_index();
  const int a = lattice_index(res, 4, 8, 4), b = lattice_index(res, 8, 8, 8);
  std::vector<Eigen::Triplet<double>> entries;
  const SparseLower& A = s.H.matrix;
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (SparseLower::InnerIterator it(A, c); it; ++it) entries.emplace_back(it.row(), it.col(), it.value());
  const double k = 0.5 * A.diagonal().mean();
  for (int d = 0; d < 3; ++d) {
    const int ra = row[3 * a + d], rb = row[3 * b + d];
    ASSERT_GE(ra, 0);
    ASSERT_GE(rb, 0);
    entries.emplace_back(ra, ra, k);
    entries.emplace_back(rb, rb, k);
    entries.emplace_back(std::max(ra, rb), std::min(ra, rb), -k);
  }
  SparseLower coupled(A.rows(), A.cols());
  coupled.setFromTriplets(entries.begin(), entries.end());
  MultigridPreconditioner M(mesh, row);
  ASSERT_TRUE(M.compute(coupled));
  ASSERT_GE(M.levels(), 2);
  const LatticeCoordinates lattice = lattice_coordinates(mesh);
  const std::vector<int>& colour = M.colours(0);
  ASSERT_EQ(colour.size(), static_cast<std::size_t>(mesh.vertex_count()));
  int moved = 0;
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    const Eigen::Vector3i at = lattice.coordinates.col(v);
    const int parity = (at.x() & 1) | (at.y() & 1) << 1 | (at.z() & 1) << 2;
    if (colour[v] == parity) continue;
    ++moved;
    EXPECT_EQ(v, std::max(a, b));
    EXPECT_GE(colour[v], 8);
  }
  EXPECT_EQ(moved, 1);
  for (int l = 0; l < M.levels(); ++l) {
    int clashes = 0;
    for (const auto& [i, j] : M.couplings(l)) clashes += M.colours(l)[i] == M.colours(l)[j];
    EXPECT_EQ(clashes, 0) << "level " << l;
  }
  std::mt19937_64 rng(2);
  std::normal_distribution<double> n;
  Eigen::VectorXd rhs(A.rows()), x;
  for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs[i] = n(rng);
  MultigridPreconditioner plain(mesh, row);
  ASSERT_TRUE(plain.compute(A));
  const int with = iterations_with(coupled, M, rhs, x), without = iterations_with(A, plain, rhs, x);
  std::cout << "CG iterations: " << with << " with the spring, " << without << " without\n";
  EXPECT_LE(with, without + 3);
}

TEST(Multigrid, SmallColoursOfContactCliquesRunInTurnAndKeepTheVCycleSymmetricAndThreadFree) {
  // Three cliques of 5 nodes of one parity coupled all with all (what contact pairs add to the pattern): 4 of
  // each leave the parity colours and take colours of their own, 4 small colours, which one thread relaxes in
  // turn behind one barrier, forward and then backward. Every level in parallel: the V-cycle is the same for
  // 1 and 2 threads, symmetric and positive, and CG converges in about the iterations of the plain box.
  const int res = 16;
  const VolumeMesh mesh = box_hexes(res);
  System s(mesh, pins(mesh), 17);
  const std::vector<int>& row = s.problem.dofs().free_index();
  const SparseLower& A = s.H.matrix;
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index c = 0; c < A.outerSize(); ++c)
    for (SparseLower::InnerIterator it(A, c); it; ++it) entries.emplace_back(it.row(), it.col(), it.value());
  const double k = 0.2 * A.diagonal().mean();
  std::vector<int> clique_nodes;
  for (int clique = 0; clique < 3; ++clique) {
    std::vector<int> nodes;
    for (int m = 0; m < 5; ++m) nodes.push_back(lattice_index(res, 2 + 2 * m, 4 + 4 * clique, 6 + 2 * (m % 2)));
    for (std::size_t i = 0; i < nodes.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        for (int d = 0; d < 3; ++d) {
          const int ra = row[3 * nodes[i] + d], rb = row[3 * nodes[j] + d];
          ASSERT_GE(ra, 0);
          ASSERT_GE(rb, 0);
          entries.emplace_back(ra, ra, k);
          entries.emplace_back(rb, rb, k);
          entries.emplace_back(std::max(ra, rb), std::min(ra, rb), -k);
        }
    clique_nodes.insert(clique_nodes.end(), nodes.begin(), nodes.end());
  }
  SparseLower coupled(A.rows(), A.cols());
  coupled.setFromTriplets(entries.begin(), entries.end());
  std::mt19937_64 rng(9);
  std::normal_distribution<double> n;
  Eigen::VectorXd x(A.rows()), y(A.rows());
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = n(rng), y[i] = n(rng);
  const int threads = omp_get_max_threads();
  Eigen::VectorXd Mx[2], My[2];
  for (int t : {1, 2}) {
    omp_set_num_threads(t);
    MultigridPreconditioner M(mesh, row);
    M.set_parallel_nodes(1);
    ASSERT_TRUE(M.compute(coupled));
    const std::vector<int>& colour = M.colours(0);
    EXPECT_EQ(*std::max_element(colour.begin(), colour.end()) + 1, 12) << "8 parities and 4 small colours";
    int outside = 0;
    for (int v : clique_nodes) outside += colour[static_cast<std::size_t>(v)] >= 8;
    EXPECT_EQ(outside, 12) << "4 nodes of each clique";
    M.apply(x, Mx[t - 1]);
    M.apply(y, My[t - 1]);
  }
  omp_set_num_threads(threads);
  EXPECT_EQ(std::memcmp(Mx[0].data(), Mx[1].data(), sizeof(double) * Mx[0].size()), 0) << "V-cycle, 1 and 2 threads";
  EXPECT_NEAR(y.dot(Mx[1]), x.dot(My[1]), 1e-12 * Mx[1].norm() * y.norm()) << "symmetric";
  EXPECT_GT(x.dot(Mx[1]), 0.0);
  MultigridPreconditioner M(mesh, row), plain(mesh, row);
  M.set_parallel_nodes(1);
  ASSERT_TRUE(M.compute(coupled));
  ASSERT_TRUE(plain.compute(A));
  Eigen::VectorXd solution;
  const int with = iterations_with(coupled, M, x, solution), without = iterations_with(A, plain, x, solution);
  std::cout << "CG iterations: " << with << " with the cliques, " << without << " without\n";
  EXPECT_LE(with, without + 3);
}

// Every coarse level's matrix is Pᵀ A P of the level above it on the coarse level's free DOFs (and zero on
// the others: those with a zero diagonal, as many as the level has DOFs that are not free), by the serial and
// the parallel product alike.
void check_galerkin(const VolumeMesh& mesh, Coarsening how) {
  System s(mesh, pins(mesh), 7);
  for (int parallel_nodes : {1, 1 << 30}) {
    MultigridPreconditioner M(mesh, s.problem.dofs().free_index(), how);
    M.set_parallel_nodes(parallel_nodes);
    ASSERT_TRUE(M.compute(s.H.matrix));
    ASSERT_GE(M.levels(), 2);
    for (int l = 0; l + 1 < M.levels(); ++l) {
      const Eigen::SparseMatrix<double> P = M.prolongation(l), A = M.level_matrix(l), C = M.level_matrix(l + 1);
      Eigen::SparseMatrix<double> expected = Eigen::SparseMatrix<double>(P.transpose()) * A * P;
      const Eigen::VectorXd diagonal = C.diagonal();
      const Eigen::Index fixed = (diagonal.array() == 0.0).count();
      EXPECT_EQ(fixed, C.rows() - M.unknowns(l + 1)) << "level " << l + 1;
      expected.prune([&](Eigen::Index r, Eigen::Index c, double) { return diagonal[r] != 0.0 && diagonal[c] != 0.0; });
      EXPECT_GT(C.norm(), 0.0);
      EXPECT_LE((C - expected).norm(), 1e-13 * expected.norm()) << "level " << l + 1 << ", parallel from " << parallel_nodes;
      EXPECT_EQ((C - Eigen::SparseMatrix<double>(C.transpose())).norm(), 0.0) << "level " << l + 1;
    }
  }
}

TEST(Multigrid, CoarseMatricesAreTheGalerkinProducts) { check_galerkin(partial_lattice(), Coarsening::lattice); }

TEST(AlgebraicMultigrid, CoarseMatricesAreTheGalerkinProducts) { check_galerkin(box_tets(6), Coarsening::aggregation); }

// amg keeps its coarse levels from an earlier Newton matrix while they serve: the V-cycle with old coarse
// levels and a new finest level is still symmetric positive definite, and CG with it converges.
TEST(AlgebraicMultigrid, OldCoarseLevelsKeepTheVCycleSymmetricPositive) {
  const VolumeMesh mesh = box_tets(10);
  System first(mesh, pins(mesh), 7), second(mesh, pins(mesh), 8);
  const SparseLower& A = second.H.matrix;
  MultigridPreconditioner M(mesh, first.problem.dofs().free_index(), Coarsening::aggregation);
  ASSERT_TRUE(M.compute(first.H.matrix));
  ASSERT_TRUE(M.compute(A, 0.0, false));
  std::mt19937_64 rng(4);
  std::normal_distribution<double> n;
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd x(A.rows()), y(A.rows()), Mx, My;
    for (Eigen::Index i = 0; i < A.rows(); ++i) x[i] = n(rng), y[i] = n(rng);
    M.apply(x, Mx);
    M.apply(y, My);
    EXPECT_NEAR(y.dot(Mx), x.dot(My), 1e-12 * Mx.norm() * y.norm());
    EXPECT_GT(x.dot(Mx), 0.0);
  }
  Eigen::VectorXd b(A.rows()), x;
  for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = n(rng);
  EXPECT_LE(iterations_with(A, M, b, x), 60);
  EXPECT_LE((A.selfadjointView<Eigen::Lower>() * x - b).norm(), 1e-10 * b.norm());
}

TEST(AlgebraicMultigrid, NeedsTheMeshBehindTheMatrixAndSaysSoInOneLine) {
  const VolumeMesh tets = box_tets(2);
  const std::vector<int> free(3 * tets.vertex_count(), 0), short_index(5, 0);
  EXPECT_TRUE(amg_applicable({.mesh = &tets, .free_index = &free}));
  EXPECT_FALSE(amg_applicable({.mesh = &tets}));
  EXPECT_FALSE(amg_applicable({.mesh = &tets, .free_index = &short_index}));
  EXPECT_FALSE(amg_applicable({}));
  try {
    (void)make_linear_solver({.name = "amg"});
    FAIL() << "amg with no mesh behind the matrix must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the multigrid solver (amg) needs the mesh behind the matrix (use cholmod, ldlt or pcg)");
  }
  EXPECT_THROW((void)make_linear_solver({.name = "amg"}, {.mesh = &tets, .free_index = &short_index}), std::invalid_argument);
  EXPECT_EQ(make_linear_solver({.name = "amg"}, {.mesh = &tets, .free_index = &free})->name(), "amg");
}

class IndefiniteMatrix : public testing::TestWithParam<const char*> {};

TEST_P(IndefiniteMatrix, SolverRecognisesItAndShiftsWhenRequired) {
  const std::string name = GetParam();
  const VolumeMesh mesh = name == "mg" ? box_hexes(6) : box_tets(6);
  System s(mesh, pins(mesh), 5);
  SparseLower A = s.H.matrix;
  for (Eigen::Index c = 0; c < A.outerSize(); ++c) A.valuePtr()[A.outerIndexPtr()[c]] -= 50.0;  // far negative diagonal
  const std::vector<int>& free = s.problem.dofs().free_index();
  auto solver = make_linear_solver({.name = name}, {.mesh = &mesh, .free_index = &free});
  EXPECT_EQ(solver->name(), name);
  EXPECT_FALSE(solver->try_factorize(A));
  EXPECT_GT(solver->factorize(A), 0.0);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  EXPECT_TRUE(solver->solve(b).allFinite());
  // And a positive definite one is solved to the tolerance.
  ASSERT_TRUE(solver->try_factorize(s.H.matrix));
  const Eigen::VectorXd x = solver->solve(b);
  EXPECT_LE((s.H.matrix.selfadjointView<Eigen::Lower>() * x - b).norm(), 1e-10 * b.norm());
  EXPECT_GT(solver->last_iterations(), 0);
}

INSTANTIATE_TEST_SUITE_P(Multigrid, IndefiniteMatrix, testing::Values("mg", "amg"));

/// Newton on the pinned box (Stable Neo-Hookean, μ 1, λ 9) from x0 with the named linear solver.
NewtonReport box_newton(const VolumeMesh& mesh, const std::vector<std::uint8_t>& kinematic, const std::string& solver,
                        const NewtonOptions& options, Eigen::VectorXd& x) {
  ElasticTerm elastic(mesh, make_material("stable_neo_hookean", Lame{1.0, 9.0}));
  Problem problem{DofMap(kinematic)};
  problem.add(elastic);
  const std::vector<int>& free = problem.dofs().free_index();
  auto linear = make_linear_solver({.name = solver}, {.mesh = &mesh, .free_index = &free});
  return newton_solve(problem, x, *linear, options);
}

// Truncated Newton: a box squashed through itself (every free vertex's height reflected through the pinned
// base and halved, so every cell is inverted) is unfolded by Newton, whose true Hessian is indefinite on the
// way. mg and amg truncate some of their conjugate-gradient solves at negative curvature (LinearSolver::
// last_truncated) instead of falling back to the projected Hessian, and reach the direct solver's rest state.
// The true Hessian is tried at every iteration here (skip_true_after_failure off: on this box mg's one
// truncated step comes right after a failed try); with the default the box reaches the same state.
class TruncatedNewton : public testing::TestWithParam<const char*> {};

TEST_P(TruncatedNewton, UnfoldsAnInvertedBoxToTheDirectSolversAnswer) {
  const std::string name = GetParam();
  const VolumeMesh mesh = name == "mg" ? box_hexes(10) : box_tets(6);  // mg: enough DOFs for two levels
  const std::vector<std::uint8_t> kinematic = pins(mesh);
  Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size());
  const double lo = mesh.vertices.row(1).minCoeff();
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!kinematic[3 * v + 1]) x0[3 * v + 1] = lo - 0.5 * (x0[3 * v + 1] - lo);
  NewtonReport report[3];
  Eigen::VectorXd x[3] = {x0, x0, x0};
  for (int k = 0; k < 3; ++k) {
    NewtonOptions options{.tolerance = 1e-8};
    options.skip_true_after_failure = k == 2;
    report[k] = box_newton(mesh, kinematic, k == 0 ? "cholmod" : name, options, x[k]);
    ASSERT_TRUE(report[k].converged) << report[k].failure;
  }
  EXPECT_NEAR(report[2].energy, report[0].energy, 1e-10);
  EXPECT_LT((x[2] - x[0]).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(report[0].truncated_steps, 0) << "a direct solver never truncates";
  EXPECT_GT(report[1].truncated_steps, 0) << name << " met no negative curvature: the box is not inverted enough to test";
  std::cout << name << ": " << report[1].iterations << " Newton iterations (" << report[1].truncated_steps << " truncated, "
            << report[1].true_hessian_steps << " on the true Hessian); with the default " << report[2].iterations << " ("
            << report[2].truncated_steps << " truncated); cholmod " << report[0].iterations << "\n";
  EXPECT_NEAR(report[1].energy, report[0].energy, 1e-10);
  EXPECT_LT((x[1] - x[0]).cwiseAbs().maxCoeff(), 1e-6);
}

// Chord steps: a box pulled up by a tenth of its height and let go; an inexact
// solver's iteration after a step within 30 times the step rule reuses the matrix it holds, and the
// answer is the direct solver's (which never takes a chord step) to the step tolerance.
class ChordStep : public testing::TestWithParam<const char*> {};

TEST_P(ChordStep, SparesANewMatrixAndKeepsTheAnswer) {
  const std::string name = GetParam();
  const VolumeMesh mesh = name == "mg" ? box_hexes(10) : box_tets(6);
  const std::vector<std::uint8_t> kinematic = pins(mesh);
  Eigen::VectorXd x0 = Eigen::Map<const Eigen::VectorXd>(mesh.vertices.data(), mesh.vertices.size());
  const double lo = mesh.vertices.row(1).minCoeff();
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!kinematic[3 * v + 1]) x0[3 * v + 1] = lo + 1.1 * (x0[3 * v + 1] - lo);
  const double step = 1e-6;  // both solvers take a step within 30 times this one before the last
  // The step rule ends a solve only where ‖g‖ is within 10 times the tolerance (newton.hpp) and never on a
  // chord step: with a tight force tolerance the solve goes on past the small steps that call for chord steps.
  NewtonReport report[2];
  Eigen::VectorXd x[2] = {x0, x0};
  for (int k = 0; k < 2; ++k) {
    report[k] = box_newton(mesh, kinematic, k == 0 ? "cholmod" : name, {.tolerance = 1e-12, .step_tolerance = step}, x[k]);
    ASSERT_TRUE(report[k].converged) << report[k].failure;
    EXPECT_LE(report[k].residual, 10.0 * 1e-12);
  }
  EXPECT_EQ(report[0].chord_steps, 0) << "a direct solver assembles every Newton matrix";
  EXPECT_GE(report[1].chord_steps, 1);
  std::cout << name << ": " << report[1].iterations << " Newton iterations (" << report[1].chord_steps << " chord); cholmod "
            << report[0].iterations << "\n";
  // Each run stops within a step of `step` of the minimum; the stiffness is of order 1 (μ = 1).
  EXPECT_LT((x[1] - x[0]).cwiseAbs().maxCoeff(), 20 * step);
}

INSTANTIATE_TEST_SUITE_P(Multigrid, ChordStep, testing::Values("mg", "amg"));

INSTANTIATE_TEST_SUITE_P(Multigrid, TruncatedNewton, testing::Values("mg", "amg"));

namespace fs = std::filesystem;

fs::path multigrid_dir(const std::string& name) { return test::fresh_dir("snh_test_mg_", name); }

using test::file_text;

/// The stretch test at res 10 (hexes: 3 267 free DOFs, a two-level hierarchy) to a 2× stretch in 8 steps.
StretchResult stretch(const std::string& solver, const fs::path& out, CellType element = CellType::hex8) {
  StretchConfig c;
  c.element = element;
  c.resolution = 10;
  c.steps = 8;
  c.stretch = 2.0;
  c.solver = solver;
  c.out = out;
  std::ostringstream log;
  return run_stretch(c, log);
}

// A whole stretch run with mg (hexes) or amg (tets) gives the direct solver's answer to the Newton tolerance
// (‖f‖ < 1e-3: each run's positions are off the exact answer by about ‖f‖ over the stiffness, 1e-4, so the
// two runs differ by up to twice that), and the same run with 1 and 2 threads is bit-identical.
class StretchRun : public testing::TestWithParam<const char*> {};

TEST_P(StretchRun, MatchesTheDirectSolverAndIsTheSameForOneAndTwoThreads) {
  const std::string solver = GetParam();
  const CellType element = solver == "mg" ? CellType::hex8 : CellType::tet4;
  const fs::path direct_dir = multigrid_dir(solver + "_direct"), one = multigrid_dir(solver + "_one"), two = multigrid_dir(solver + "_two");
  const StretchResult direct = stretch("cholmod", direct_dir, element);
  omp_set_num_threads(1);
  const StretchResult mg1 = stretch(solver, one, element);
  omp_set_num_threads(2);
  const StretchResult mg2 = stretch(solver, two, element);
  ASSERT_TRUE(direct.all_converged && mg1.all_converged && mg2.all_converged);
  EXPECT_NEAR(mg1.middle_width, direct.middle_width, 1e-4);
  int cg = 0;
  for (const StepStats& s : mg1.steps) cg += s.linear_iterations;
  EXPECT_GT(cg, 0) << "conjugate gradients ran";
  // Every frame's positions (OBJ, 10 significant digits) within 2e-4 of the direct solver's.
  std::istringstream a(file_text(direct_dir / "008.obj")), b(file_text(one / "008.obj"));
  double worst = 0.0;
  for (std::string la, lb; std::getline(a, la) && std::getline(b, lb);) {
    if (la.rfind("v ", 0) != 0) continue;
    std::istringstream pa(la.substr(2)), pb(lb.substr(2));
    for (int k = 0; k < 3; ++k) {
      double x = 0, y = 0;
      pa >> x;
      pb >> y;
      worst = std::max(worst, std::abs(x - y));
    }
  }
  EXPECT_LT(worst, 2e-4);
  EXPECT_GT(worst, 0.0) << "CG and the direct solver stop at different residuals";
  // The exact state (checkpoint.bin holds the positions as doubles) and the frames: bit-identical.
  EXPECT_EQ(file_text(one / "checkpoint.bin"), file_text(two / "checkpoint.bin"));
  EXPECT_EQ(file_text(one / "008.vtu"), file_text(two / "008.vtu"));
  for (const fs::path& d : {direct_dir, one, two}) fs::remove_all(d);
}

INSTANTIATE_TEST_SUITE_P(MultigridRuns, StretchRun, testing::Values("mg", "amg"));

TEST(MultigridRuns, TetMeshesAreRefusedWithOneLine) {
  StretchConfig c;
  c.element = CellType::tet4;
  c.resolution = 3;
  c.solver = "mg";
  c.out = multigrid_dir("tets");
  std::ostringstream log;
  try {
    (void)run_stretch(c, log);
    FAIL() << "mg on tets must be refused";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("hexahedral lattice"), std::string::npos) << e.what();
  }
  fs::remove_all(c.out);
}

// A flesh lattice (only the cubes that overlap a bent limb, its bone-bound vertices kinematic) with mg, and
// the limb's tet mesh with amg: the direct solver's answer.
class FleshRun : public testing::TestWithParam<const char*> {};

TEST_P(FleshRun, MatchesTheDirectSolver) {
  const std::string multigrid = GetParam();
  const fs::path dir = multigrid_dir("flesh_" + multigrid);
  fs::create_directories(dir);
  test::write_limb_gltf(dir / "limb.gltf");
  Eigen::VectorXd x[2];
  int k = 0;
  for (const std::string& solver : {std::string("cholmod"), multigrid}) {
    const nlohmann::json j = {
        {"flesh", {{"model", (dir / "limb.gltf").string()}, {"volume", multigrid == "mg" ? "lattice" : "tets"}, {"resolution", 24}}},
        {"frames", 3},
        {"solver", {{"linear", solver}}},
        {"output", {{"dir", (dir / solver).string()}}}};
    const Scene s = parse_scene(j, dir / "limb.json");
    std::ostringstream log;
    const SceneResult r = run_scene(s, log);
    ASSERT_TRUE(r.all_converged) << solver << ": " << r.failure;
    if (k == 0) std::cout << r.vertices << " vertices, " << r.cells << " cells\n";
    x[k++] = r.final_positions;
  }
  const double size = x[0].cwiseAbs().maxCoeff();
  EXPECT_LT((x[1] - x[0]).cwiseAbs().maxCoeff(), 1e-5 * size);
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(MultigridRuns, FleshRun, testing::Values("mg", "amg"));

}  // namespace
}  // namespace snh
