// The problem layer: the DOF map, Hessian layouts (any numbering, covers, add_block), a sum of terms
// checked against finite differences, and a layout that grows when a term's stencil moves.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <random>

#include "snh/fem/attachment_term.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/mesh/box.hpp"
#include "fem/problem_fd.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using test::flatten;

/// Springs k/2 (|x_a − x_b| − L)² between vertex pairs; the pairs may be chosen by x (varying stencil):
/// when `follow` is set, vertex 0 is also tied to whichever vertex is farthest from it.
class Springs final : public Term {
 public:
  Springs(std::vector<std::array<int, 2>> pairs, double k, double rest, bool follow = false)
      : pairs_(std::move(pairs)), k_(k), rest_(rest), follow_(follow) {}
  std::string_view name() const override { return "springs"; }
  double energy(const Eigen::VectorXd& x) const override { return evaluate(x, nullptr, nullptr, PsdProjection::none); }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, const HessianValues* H, PsdProjection) const override {
    double E = 0.0;
    for (const auto& [a, b] : current(x)) {
      const Eigen::Vector3d d = x.segment<3>(3 * a) - x.segment<3>(3 * b);
      const double l = d.norm(), s = l - rest_;
      E += 0.5 * k_ * s * s;
      const Eigen::Vector3d n = d / l;
      if (g) {
        g->segment<3>(3 * a) += k_ * s * n;
        g->segment<3>(3 * b) -= k_ * s * n;
      }
      if (H) {
        const Mat3 K = k_ * (n * n.transpose() + (s / l) * (Mat3::Identity() - n * n.transpose()));
        H->add_block(a, a, K);
        H->add_block(b, b, K);
        H->add_block(a, b, -K);
      }
    }
    return E;
  }
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override {
    out.arity = 2;
    out.vertices.clear();
    for (const auto& [a, b] : current(x)) out.vertices.insert(out.vertices.end(), {a, b});
  }
  bool stencil_varies() const override { return follow_; }

 private:
  std::vector<std::array<int, 2>> current(const Eigen::VectorXd& x) const {
    std::vector<std::array<int, 2>> p = pairs_;
    if (follow_ && x.size() > 0) {
      int far = 1;
      for (int v = 1; v < x.size() / 3; ++v)
        if ((x.segment<3>(3 * v) - x.segment<3>(0)).norm() > (x.segment<3>(3 * far) - x.segment<3>(0)).norm()) far = v;
      p.push_back({0, far});
    }
    return p;
  }
  std::vector<std::array<int, 2>> pairs_;
  double k_, rest_;
  bool follow_;
};

TEST(DofMap, NumbersFreeDofsInOrder) {
  const DofMap m({0, 1, 0, 0, 1, 1});
  EXPECT_EQ(m.dofs(), 6);
  EXPECT_EQ(m.free_count(), 3);
  EXPECT_EQ(m.free_index(), (std::vector<int>{0, -1, 1, 2, -1, -1}));
  const Eigen::VectorXd full = Eigen::VectorXd::LinSpaced(6, 1, 6);
  EXPECT_EQ(m.gather_free(full), Eigen::Vector3d(1, 3, 4));
  Eigen::VectorXd y = full;
  m.scatter_add_free(Eigen::Vector3d(1, 1, 1), 2.0, y);
  EXPECT_EQ(y, (Eigen::VectorXd(6) << 3, 2, 5, 6, 5, 6).finished());
  EXPECT_EQ(m.expand(Eigen::Vector3d(7, 8, 9)), (Eigen::VectorXd(6) << 7, 0, 8, 9, 0, 0).finished());
}

TEST(HessianLayout, AnyNumberingGivesSortedLowerColumnsStartingAtTheDiagonal) {
  // Two vertices coupled, a third alone; DOFs numbered in a scrambled order, one DOF left out.
  const Stencil pair{.arity = 2, .vertices = {0, 2}};
  std::vector<int> numbering = {4, 0, 6, -1, 7, 1, 2, 5, 3};
  const HessianLayout L(numbering, 8, {&pair});
  const SparseLower& P = L.pattern();
  ASSERT_EQ(P.rows(), 8);
  for (Eigen::Index c = 0; c < P.outerSize(); ++c) {
    const int first = P.outerIndexPtr()[c], last = P.outerIndexPtr()[c + 1];
    ASSERT_LT(first, last);
    EXPECT_EQ(P.innerIndexPtr()[first], c) << "column " << c << " starts at its diagonal";
    for (int k = first + 1; k < last; ++k) EXPECT_LT(P.innerIndexPtr()[k - 1], P.innerIndexPtr()[k]);
  }
  // Vertex 1's DOFs (numbers 7, 1) couple only with themselves; vertices 0 and 2 with each other.
  EXPECT_GE(L.entry(7, 1), 0);
  EXPECT_EQ(L.entry(7, 0), -1);
  EXPECT_GE(L.entry(5, 4), 0);  // vertex 2 (its y: 5) with vertex 0 (its x: 4)
  EXPECT_TRUE(L.covers(pair));
  EXPECT_FALSE(L.covers(Stencil{.arity = 2, .vertices = {0, 1}}));
  EXPECT_NE(L.id(), HessianLayout(numbering, 8, {&pair}).id()) << "every layout has its own id";
  EXPECT_THROW(HessianLayout(numbering, 9, {&pair}), std::invalid_argument) << "number 8 unused";
  numbering[1] = 4;
  EXPECT_THROW(HessianLayout(numbering, 8, {&pair}), std::invalid_argument) << "number 4 twice";
}

TEST(HessianLayout, ALargeLayoutIsEveryCoupledPairOnceForAnyThreadCountAndMovesWithoutCopying) {
  // Enough vertices to build on all threads: random groups of 2 to 8 vertices, some vertices in none, a
  // scrambled numbering with DOFs left out (its columns then need sorting). Against the pairs counted one by one.
  std::mt19937 rng(7);
  const int vertices = 6000;
  std::vector<int> numbering(3 * vertices);
  std::iota(numbering.begin(), numbering.end(), 0);
  std::shuffle(numbering.begin(), numbering.end(), rng);
  int size = 0;
  std::vector<int> order(numbering.size());
  for (std::size_t d = 0; d < numbering.size(); ++d) order[static_cast<std::size_t>(numbering[d])] = static_cast<int>(d);
  std::fill(numbering.begin(), numbering.end(), -1);
  for (int d : order)
    if (d % 7 != 3) numbering[static_cast<std::size_t>(d)] = size++;
  Stencil quads{.arity = 4, .vertices = {}}, octets{.arity = 8, .vertices = {}};
  std::uniform_int_distribution<int> pick(0, vertices - 200);  // the last 200 vertices in no group
  for (int g = 0; g < 3000; ++g)
    for (int k = 0; k < 4; ++k) quads.vertices.push_back(pick(rng));
  for (int g = 0; g < 2000; ++g) {
    const int base = pick(rng);
    for (int k = 0; k < 8; ++k) octets.vertices.push_back(std::min(vertices - 1, base + 3 * k));
  }
  std::set<std::pair<int, int>> expected;  // (row, column), row ≥ column: each vertex's own block, and the groups'
  for (int v = 0; v < vertices; ++v)
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        const int r = numbering[static_cast<std::size_t>(3 * v + i)], c = numbering[static_cast<std::size_t>(3 * v + k)];
        if (r >= 0 && c >= 0 && r >= c) expected.emplace(r, c);
      }
  for (const Stencil* s : {&quads, &octets})
    for (Eigen::Index g = 0; g < s->groups(); ++g)
      for (int a = 0; a < s->arity; ++a)
        for (int b = 0; b < s->arity; ++b)
          for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) {
              const int r = numbering[3 * static_cast<std::size_t>(s->vertices[g * s->arity + a]) + i];
              const int c = numbering[3 * static_cast<std::size_t>(s->vertices[g * s->arity + b]) + k];
              if (r >= 0 && c >= 0 && r >= c) expected.emplace(r, c);
            }
  std::vector<std::vector<int>> inner_by_threads;
  const int max_threads = omp_get_max_threads();
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    HessianLayout L(numbering, size, {&quads, &octets});
    const SparseLower& P = L.pattern();
    ASSERT_EQ(P.nonZeros(), static_cast<Eigen::Index>(expected.size())) << threads << " threads";
    std::set<std::pair<int, int>> got;
    for (Eigen::Index c = 0; c < P.outerSize(); ++c) {
      const int first = P.outerIndexPtr()[c], last = P.outerIndexPtr()[c + 1];
      ASSERT_LT(first, last);
      EXPECT_EQ(P.innerIndexPtr()[first], c) << "column " << c << " starts at its diagonal";
      for (int k = first; k < last; ++k) {
        if (k > first) ASSERT_LT(P.innerIndexPtr()[k - 1], P.innerIndexPtr()[k]) << "column " << c;
        EXPECT_EQ(P.valuePtr()[k], 0.0);
        got.emplace(P.innerIndexPtr()[k], static_cast<int>(c));
      }
    }
    EXPECT_EQ(got, expected) << threads << " threads";
    EXPECT_TRUE(L.covers(quads) && L.covers(octets));
    inner_by_threads.emplace_back(P.innerIndexPtr(), P.innerIndexPtr() + P.nonZeros());
    // A move hands the storage over (Eigen 3.4's SparseMatrix would copy it): the same arrays, the same id.
    const int* storage = P.innerIndexPtr();
    const std::uint64_t id = L.id();
    HessianLayout moved(std::move(L));
    EXPECT_EQ(moved.pattern().innerIndexPtr(), storage);
    EXPECT_EQ(moved.id(), id);
    HessianLayout assigned;
    assigned = std::move(moved);
    EXPECT_EQ(assigned.pattern().innerIndexPtr(), storage);
    EXPECT_EQ(assigned.id(), id);
    EXPECT_EQ(assigned.entry(size - 1, size - 1), static_cast<int>(expected.size()) - 1) << "the last diagonal ends it";
  }
  omp_set_num_threads(max_threads);
  EXPECT_EQ(inner_by_threads[0], inner_by_threads[1]);
}

TEST(HessianLayout, AddBlockFillsTheLowerTriangleAndSkipsKinematicDofs) {
  const Stencil pair{.arity = 2, .vertices = {0, 1}};
  const DofMap dofs({0, 0, 1, 0, 0, 0});  // vertex 0's z is kinematic
  const HessianLayout L(dofs.free_index(), 5, {&pair});
  std::vector<double> values(L.pattern().nonZeros(), 0.0);
  const HessianValues H(L, values.data());
  Mat3 A, B;
  A << 4, 1, 2, 1, 5, 3, 2, 3, 6;
  B << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  H.add_block(0, 0, A);
  H.add_block(1, 1, A);
  H.add_block(0, 1, B);
  SparseLower M = L.pattern();
  std::copy(values.begin(), values.end(), M.valuePtr());
  const Eigen::MatrixXd dense = Eigen::MatrixXd(M).selfadjointView<Eigen::Lower>();
  Eigen::MatrixXd full = Eigen::MatrixXd::Zero(6, 6);
  full.block<3, 3>(0, 0) = A;
  full.block<3, 3>(3, 3) = A;
  full.block<3, 3>(0, 3) = B;
  full.block<3, 3>(3, 0) = B.transpose();
  const std::vector<int> keep = {0, 1, 3, 4, 5};
  EXPECT_EQ(dense, full(keep, keep));
  EXPECT_THROW(HessianValues(HessianLayout(dofs.free_index(), 5, {}), values.data()).add_block(0, 1, B), std::logic_error);
}

TEST(Problem, SumsItsTermsAndMatchesFiniteDifferences) {
  const VolumeMesh m = box_tets(2);
  std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
  for (int d : {0, 1, 2, 7}) fixed[d] = 1;
  ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
  Springs springs({{0, 26}, {5, 20}, {3, 3 + 9}}, 2.0, 0.5);  // far apart in the mesh: the layout must couple them
  Problem p{DofMap(fixed)};
  p.add(elastic);
  p.add(springs);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = 1.1 * x[i] + n(rng);
  Eigen::VectorXd g;
  HessianMatrix H;
  const double E = p.evaluate(x, g, &H, PsdProjection::none);
  EXPECT_DOUBLE_EQ(E, elastic.energy(x) + springs.energy(x));
  EXPECT_DOUBLE_EQ(E, p.energy(x));
  const FdErrors e = problem_fd_errors(p, x);
  EXPECT_LE(e.gradient, 1e-8);
  EXPECT_LE(e.hessian, 1e-8);
  EXPECT_EQ(p.layouts_built(), 1);
}

TEST(Problem, TheLayoutGrowsWhenAVaryingStencilLeavesIt) {
  const VolumeMesh m = box_hexes(2);
  ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
  Springs follow({}, 1.0, 0.1, true);  // vertex 0 tied to the vertex farthest from it
  Problem p{DofMap(std::vector<std::uint8_t>(3 * m.vertex_count(), 0))};
  p.add(elastic);
  p.add(follow);
  // box_hexes(2): vertex i + 3j + 9k at (i−1, j−1, k−1); vertex 0 shares a cell only with i, j, k ≤ 1.
  Eigen::VectorXd x = flatten(m.vertices), g;
  HessianMatrix H;
  p.evaluate(x, g, &H, PsdProjection::clamp);  // the farthest from vertex 0 is vertex 26: (0, 26) in the layout
  EXPECT_EQ(p.layouts_built(), 1);
  const std::uint64_t first = H.layout;
  p.evaluate(x * 1.01, g, &H, PsdProjection::clamp);  // the same pair: no rebuild
  EXPECT_EQ(p.layouts_built(), 1);
  EXPECT_EQ(H.layout, first);
  x.segment<3>(3 * 1) = Eigen::Vector3d(9, -1, -1);  // vertex 1 far away: (0, 1) share a cell, covered
  p.evaluate(x, g, &H, PsdProjection::clamp);
  EXPECT_EQ(p.layouts_built(), 1);
  EXPECT_EQ(H.layout, first);
  x = flatten(m.vertices);
  x.segment<3>(3 * 8) = Eigen::Vector3d(9, 9, -1);  // vertex 8 = (1, 1, −1) far away: (0, 8) share no cell
  p.evaluate(x, g, &H, PsdProjection::clamp);
  EXPECT_EQ(p.layouts_built(), 2) << "the layout grew";
  EXPECT_NE(H.layout, first);
  // The grown matrix equals a fresh problem's over the same pairs.
  Springs fixed_pair({{0, 8}}, 1.0, 0.1);
  Problem q{DofMap(std::vector<std::uint8_t>(3 * m.vertex_count(), 0))};
  q.add(elastic);
  q.add(fixed_pair);
  Eigen::VectorXd gq;
  HessianMatrix Hq;
  q.evaluate(x, gq, &Hq, PsdProjection::clamp);
  EXPECT_EQ(g, gq);
  EXPECT_EQ(Eigen::MatrixXd(H.matrix), Eigen::MatrixXd(Hq.matrix));
}

TEST(AttachmentTerm, PullsTowardTargetsThatMoveWithTimeAndMatchesFiniteDifferences) {
  const VolumeMesh m = box_tets(2);
  std::vector<std::uint8_t> fixed(3 * m.vertex_count(), 0);
  for (int d : {0, 1, 2}) fixed[d] = 1;  // vertex 0 kinematic: its spring moves no free DOF
  ElasticTerm elastic(m, make_material("stable_neo_hookean", {1.0, 10.0}));
  const std::vector<int> attached{0, 13, 22, 7};
  const Eigen::Vector4d k(3.0, 1.0, 2.5, 0.0);
  AttachmentTerm springs(attached, k, [&](double t, Eigen::Matrix3Xd& out) {
    out = m.vertices(Eigen::all, attached);
    out.row(0).array() += t;           // targets slide along x with time
    out.row(2).array() -= 0.5 * t * t;
  });
  Problem p{DofMap(fixed)};
  p.add(elastic);
  p.add(springs);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd x = flatten(m.vertices);
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += n(rng);
  for (double t : {0.0, 0.7}) {
    p.at_time(t);
    double expected = 0.0;  // ½ Σ k |x − target|², written out
    for (std::size_t i = 0; i < attached.size(); ++i) {
      Eigen::Vector3d target = m.vertices.col(attached[i]);
      target += Eigen::Vector3d(t, 0.0, -0.5 * t * t);
      expected += 0.5 * k[static_cast<Eigen::Index>(i)] * (x.segment<3>(3 * attached[i]) - target).squaredNorm();
    }
    EXPECT_NEAR(springs.energy(x), expected, 1e-14 * (1.0 + expected)) << "t = " << t;
    const FdErrors e = problem_fd_errors(p, x);
    EXPECT_LE(e.gradient, 1e-8) << "t = " << t;
    EXPECT_LE(e.hessian, 1e-8) << "t = " << t;
  }
  // At its targets the term adds no force: the problem's gradient is the elastic one.
  Eigen::VectorXd y = x, g_all, g_elastic;
  for (std::size_t i = 0; i < attached.size(); ++i) y.segment<3>(3 * attached[i]) = springs.targets().col(static_cast<Eigen::Index>(i));
  p.evaluate(y, g_all, nullptr, PsdProjection::none);
  Problem only_elastic{DofMap(fixed)};
  only_elastic.add(elastic);
  only_elastic.evaluate(y, g_elastic, nullptr, PsdProjection::none);
  EXPECT_EQ(g_all, g_elastic);
}

TEST(AttachmentTerm, RefusesInconsistentInput) {
  auto none = [](double, Eigen::Matrix3Xd& out) { out.setZero(3, 2); };
  EXPECT_THROW(AttachmentTerm({1, 1}, Eigen::Vector2d(1, 1), none), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, -2}, Eigen::Vector2d(1, 1), none), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, 2}, Eigen::Vector2d(1, -1), none), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, 2}, Eigen::Vector2d(1, std::nan("")), none), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, 2}, Eigen::Vector3d(1, 1, 1), none), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, 2}, Eigen::Vector2d(1, 1), {}), std::invalid_argument);
  EXPECT_THROW(AttachmentTerm({1, 2, 3}, Eigen::Vector3d(1, 1, 1), none), std::logic_error) << "2 targets for 3 vertices";
}

}  // namespace
}  // namespace snh
