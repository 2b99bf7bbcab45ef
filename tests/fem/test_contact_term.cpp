// The contact terms (IPC barrier over a triangle surface, and a ground plane): derivatives of the whole
// term by finite differences with vertex–triangle, edge–edge and mollified edge–edge pairs; how duplicate
// candidates merge (a vertex over a shared edge or a shared vertex) and why they keep their weights (the
// energy stays continuous across a closest-feature change); that max_step keeps every pair apart on random
// steps of two approaching cubes (an intersection test of its own below); that a term with nothing in
// range changes nothing, bit for bit; and two physics runs: a cube dropped on the ground comes to rest
// above it, two cubes thrown at each other bounce apart, never intersecting.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <random>

#include "snh/contact/barrier.hpp"
#include "snh/contact/broad_phase.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/fem/attachment_term.hpp"
#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/dynamics.hpp"
#include "snh/sim/simulation.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/newton.hpp"
#include "contact/surface_checks.hpp"
#include "fem/problem_fd.hpp"
#include "fem/weighted_points.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

using testing::identity_through_weights;

using Kind = ContactPair::Kind;

using test::flatten;
/// A plane through p with normal n (any length: the term normalises it) as a collider shape.
ColliderShape plane(const Vec3& p, const Vec3& n) { return {ColliderShape::Kind::plane, p, n, 0.0}; }

using test::unflatten;

/// Tet A = (0,0,0), (1,0,0), (0,1,0), (0,0,−1) (its top face on z = 0) and tet B = vertices 4..7.
struct TwoTets {
  Eigen::Matrix3Xd V{3, 8};
  Eigen::Matrix3Xi F{3, 8};
  explicit TwoTets(const Eigen::Matrix<double, 3, 4>& B) {
    V.leftCols<4>() << 0, 1, 0, 0,  //
        0, 0, 1, 0,                  //
        0, 0, 0, -1;
    V.rightCols<4>() = B;
    const int faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
    for (int t = 0; t < 2; ++t)
      for (int f = 0; f < 4; ++f)
        for (int k = 0; k < 3; ++k) F(k, 4 * t + f) = faces[f][k] + 4 * t;
  }
};

bool has_kind(const std::vector<ContactPair>& pairs, Kind kind) {
  for (const ContactPair& p : pairs)
    if (p.kind == kind) return true;
  return false;
}

void expect_matches_finite_differences(const TwoTets& tets, double dhat, double kappa) {
  ContactTerm term(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, dhat, kappa);
  Problem problem(DofMap(std::vector<std::uint8_t>(24, 0)));
  problem.add(term);
  const Eigen::VectorXd x = flatten(tets.V);
  Eigen::VectorXd g;
  EXPECT_EQ(problem.energy(x), problem.evaluate(x, g, nullptr, PsdProjection::none));
  EXPECT_GT(problem.energy(x), 0.0);
  const FdErrors e = problem_fd_errors(problem, x);
  EXPECT_LE(e.gradient, 1e-6);
  EXPECT_LE(e.hessian, 1e-6);
  // The projected Hessian is PSD.
  HessianMatrix H;
  problem.evaluate(x, g, &H, PsdProjection::clamp);
  const Eigen::MatrixXd Hd = Eigen::MatrixXd(H.matrix).selfadjointView<Eigen::Lower>();
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hd).eigenvalues().minCoeff(), -1e-9 * Hd.norm());
}

Eigen::Matrix<double, 3, 4> jitter(Eigen::Matrix<double, 3, 4> B, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  for (int i = 0; i < B.size(); ++i) B.data()[i] += u(rng);
  return B;
}

TEST(ContactTerm, VertexTriangleAndEdgeEdgePairsMatchFiniteDifferences) {
  // B's edge (4, 5) crosses over A's edge (0, 1) 0.04 above it, and vertex 5 is 0.04 above A's top face.
  Eigen::Matrix<double, 3, 4> B;
  B << 0.5, 0.5, 0.3, 0.8,  //
      -0.3, 0.3, 0.0, 0.0,  //
      0.04, 0.04, 1.0, 1.0;
  for (unsigned seed : {1u, 2u, 3u}) {
    const TwoTets tets(jitter(B, seed));
    const ContactTerm term(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, 10.0);
    const auto pairs = term.pairs(flatten(tets.V));
    EXPECT_TRUE(has_kind(pairs, Kind::point_triangle));
    EXPECT_TRUE(has_kind(pairs, Kind::edge_edge));
    expect_matches_finite_differences(tets, 0.1, 10.0);
  }
}

TEST(ContactTerm, MollifiedEdgeEdgeAndPointEdgePairsMatchFiniteDifferences) {
  // B's edge (4, 5) runs nearly parallel to A's edge (0, 1) (|a×b|² = 1e-4 below ε ≈ 3.6e-4: mollified),
  // its endpoints just outside A beside that edge (point–edge pairs with both faces at the edge).
  Eigen::Matrix<double, 3, 4> B;
  B << 0.2, 0.8, 0.3, 0.7,     //
      -0.02, -0.01, -0.4, -0.4,  //
      0.05, 0.05, 1.0, 1.0;
  for (unsigned seed : {4u, 5u}) {
    const TwoTets tets(jitter(B, seed));
    const ContactTerm term(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, 10.0);
    const Eigen::VectorXd x = flatten(tets.V);
    bool mollified = false;
    for (const ContactPair& p : term.pairs(x))
      if (p.kind == Kind::edge_edge) {
        const auto& v = p.vertices;
        const double cross = (tets.V.col(v[1]) - tets.V.col(v[0])).cross(tets.V.col(v[3]) - tets.V.col(v[2])).squaredNorm();
        mollified = mollified || cross < p.mollifier_threshold;
      }
    EXPECT_TRUE(mollified);
    EXPECT_TRUE(has_kind(term.pairs(x), Kind::point_edge));
    expect_matches_finite_differences(tets, 0.1, 10.0);
  }
}

/// A roof: ridge edge (0, 1) shared by triangles (0, 1, 2) and (1, 0, 3); a triangle (4, 5, 6) hangs over it,
/// its vertex 4 at (x, y, h) above the ridge, its other vertices far up.
struct Roof {
  Eigen::Matrix3Xd V{3, 7};
  Eigen::Matrix3Xi F{3, 3};
  Roof(double x, double y, double h) {
    V << -1, 1, 0, 0, x, x, x,  //
        0, 0, 1, -1, y, y + 0.6, y - 0.6,  //
        0, 0, -0.5, -0.5, h, h + 1.5, h + 1.5;
    F << 0, 1, 4,  //
        1, 0, 5,   //
        2, 3, 6;
  }
};

TEST(ContactTerm, AVertexOverASharedEdgeIsOnePairWeightedByItsCandidates) {
  const Roof roof(0.1, 0.0, 0.05);
  const double dhat = 0.1, kappa = 3.0;
  const ContactTerm term(roof.F, EmbeddedPoints::every(roof.V.cols()), roof.V, dhat, kappa);
  const Eigen::VectorXd x = flatten(roof.V);
  const auto pairs = term.pairs(x);
  // Four candidates reduce to the point–edge pair (4, ridge): vertex 4 against both roof triangles, and
  // its two edges (4, 5), (4, 6) against the ridge (their closest points are vertex 4 and the ridge's
  // interior). One pair, computed once, weight 4: E = κ·4·b(0.05², d̂²).
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].kind, Kind::point_edge);
  EXPECT_EQ(pairs[0].vertices, (std::array<int, 4>{4, 0, 1, -1}));
  EXPECT_EQ(pairs[0].weight, 4);
  EXPECT_NEAR(term.energy(x), kappa * 4 * contact::barrier(0.05 * 0.05, dhat * dhat), 1e-12 * term.energy(x));
  EXPECT_NEAR(term.min_distance(x), 0.05, 1e-15);
}

TEST(ContactTerm, AVertexOverASharedVertexIsOnePairWeightedByItsCandidates) {
  // A cone of k = 5 triangles around apex 0 (ring at z = −0.5); vertex 6 hangs 0.05 above the apex with its
  // triangle (6, 7, 8) going up. Candidates: vertex 6 against each of the 5 triangles (closest: the apex),
  // each of the 5 spokes (0, ring) against the two edges (6, 7), (6, 8) (closest: the two endpoints 0 and
  // 6), and the apex against triangle (6, 7, 8) (closest: vertex 6): 16 candidates, one point–point pair.
  const int k = 5;
  Eigen::Matrix3Xd V(3, k + 4);
  V.col(0) = Vec3(0, 0, 0);
  for (int i = 0; i < k; ++i) V.col(1 + i) = Vec3(std::cos(2 * M_PI * i / k), std::sin(2 * M_PI * i / k), -0.5);
  V.col(k + 1) = Vec3(0.01, 0.02, 0.05);
  V.col(k + 2) = Vec3(0.5, 0.02, 1.5);
  V.col(k + 3) = Vec3(-0.5, 0.02, 1.5);
  Eigen::Matrix3Xi F(3, k + 1);
  for (int i = 0; i < k; ++i) F.col(i) << 0, 1 + i, 1 + (i + 1) % k;
  F.col(k) << k + 1, k + 2, k + 3;
  const ContactTerm term(F, EmbeddedPoints::every(V.cols()), V, 0.1, 1.0);
  const auto pairs = term.pairs(flatten(V));
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0].kind, Kind::point_point);
  EXPECT_EQ(pairs[0].vertices, (std::array<int, 4>{0, k + 1, -1, -1}));
  EXPECT_EQ(pairs[0].weight, 3 * k + 1);
  const double s = V.col(k + 1).squaredNorm();
  EXPECT_NEAR(term.energy(flatten(V)), (3 * k + 1) * contact::barrier(s, 0.01), 1e-12 * term.energy(flatten(V)));
}

TEST(ContactTerm, EnergyIsContinuousAcrossAClosestFeatureChange) {
  // Vertex 4 slides across the ridge (y from −0.03 to 0.03, 0.05 above it): for each roof triangle its
  // closest feature switches between the ridge and the triangle's interior. With the candidates' weights
  // the energy is continuous (each step changes it by O(step)); counting each key once would make it jump
  // by a whole pair's barrier where a triangle's interior takes over from the shared edge.
  const double dhat = 0.1;
  const int n = 3001;
  double largest_jump = 0.0, largest = 0.0;
  bool seen_triangle = false, seen_edge_only = false;
  double previous = 0.0;
  for (int i = 0; i < n; ++i) {
    const double y = -0.03 + 0.06 * i / (n - 1);
    const Roof roof(0.1, y, 0.05);
    const ContactTerm term(roof.F, EmbeddedPoints::every(roof.V.cols()), roof.V, dhat, 1.0);
    const Eigen::VectorXd x = flatten(roof.V);
    const auto pairs = term.pairs(x);
    (has_kind(pairs, Kind::point_triangle) ? seen_triangle : seen_edge_only) = true;
    const double e = term.energy(x);
    if (i > 0) largest_jump = std::max(largest_jump, std::abs(e - previous));
    largest = std::max(largest, e);
    previous = e;
  }
  EXPECT_TRUE(seen_triangle);
  EXPECT_TRUE(seen_edge_only);
  EXPECT_LT(largest_jump, 1e-3 * largest);  // a jump of one pair's barrier would be ~25% of it
}

/// Two cubes of side `side` (box_tets(res) scaled), the second shifted by `offset`, as one mesh.
struct TwoCubes {
  VolumeMesh mesh;
  Eigen::Matrix3Xi F;
  TwoCubes(double side, const Vec3& offset, int res = 1) {
    const VolumeMesh one = box_tets(res);
    const Eigen::Index n = one.vertex_count();
    mesh = one;
    mesh.vertices.resize(3, 2 * n);
    mesh.vertices.leftCols(n) = 0.5 * side * one.vertices;
    mesh.vertices.rightCols(n) = (0.5 * side * one.vertices).colwise() + offset;
    mesh.cells.resize(one.cells.rows(), 2 * one.cells.cols());
    mesh.cells.leftCols(one.cells.cols()) = one.cells;
    mesh.cells.rightCols(one.cells.cols()) = one.cells.array() + static_cast<int>(n);
    F = boundary_triangles(mesh);
  }
};

TEST(ContactTerm, StencilAheadCouplesEveryPairWithinItsReachAndCoversTheStencil) {
  // Two finer cubes (box_tets(3) scaled: 18 triangles a face), 0.6 d̂ apart and jittered by up to 0.2 d̂:
  // every vertex–triangle and edge–edge pair within layout_reach() = 4 d̂ has its four vertices coupled in a
  // layout built from stencil_ahead, as has every active pair; pairs far beyond the reach are not.
  const double dhat = 0.05;
  const TwoCubes cubes(1.0, Vec3(1.0 + 0.6 * dhat, 0.1, 0.0), 3);
  const VolumeMesh& mesh = cubes.mesh;
  const Eigen::Matrix3Xi& F = cubes.F;
  const Eigen::Index n = mesh.vertex_count() / 2;
  const ContactTerm term(F, EmbeddedPoints::every(2 * n), mesh.vertices, dhat, 1.0);
  ASSERT_DOUBLE_EQ(term.layout_reach(), 4.0 * dhat);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.2 * dhat, 0.2 * dhat);
  Eigen::Matrix3Xd V = mesh.vertices;
  for (Eigen::Index v = n; v < 2 * n; ++v) V.col(v) += Vec3(u(rng), u(rng), u(rng));
  const Eigen::VectorXd x = flatten(V);
  Stencil now, ahead;
  term.stencil(x, now);
  term.stencil_ahead(x, ahead);
  ASSERT_GT(now.groups(), 0) << "pairs in range";
  std::vector<int> numbering(x.size());
  std::iota(numbering.begin(), numbering.end(), 0);
  const HessianLayout L(numbering, static_cast<int>(x.size()), {&ahead});
  EXPECT_TRUE(L.covers(now));
  const double reach2 = std::pow(term.layout_reach(), 2);
  const Eigen::Matrix2Xi E = contact::surface_edges(F);
  const auto coupled = [&](const std::array<int, 4>& ids) {
    return L.covers(Stencil{.arity = 4, .vertices = {ids[0], ids[1], ids[2], ids[3]}});
  };
  int within = 0;
  for (Eigen::Index t = 0; t < F.cols(); ++t)
    for (Eigen::Index v = 0; v < 2 * n; ++v) {
      if ((v < n) == (F(0, t) < n)) continue;  // one cube against the other
      const std::array<int, 4> ids{static_cast<int>(v), F(0, t), F(1, t), F(2, t)};
      if (contact::point_triangle_distance(V.col(v), V.col(F(0, t)), V.col(F(1, t)), V.col(F(2, t))) < reach2) {
        ++within;
        EXPECT_TRUE(coupled(ids)) << "vertex " << v << ", triangle " << t;
      }
    }
  for (Eigen::Index a = 0; a < E.cols(); ++a)
    for (Eigen::Index b = a + 1; b < E.cols(); ++b) {
      if ((E(0, a) < n) == (E(0, b) < n)) continue;
      const std::array<int, 4> ids{E(0, a), E(1, a), E(0, b), E(1, b)};
      if (contact::edge_edge_distance(V.col(ids[0]), V.col(ids[1]), V.col(ids[2]), V.col(ids[3])) < reach2) {
        ++within;
        EXPECT_TRUE(coupled(ids)) << "edges " << a << ", " << b;
      }
    }
  EXPECT_GT(within, now.groups() / 6) << "more pairs within the reach than in range";
  // Two vertices of a candidate within the reach are at most the reach plus two edges apart: farther ones are
  // never coupled across the cubes.
  double edge = 0.0;
  for (Eigen::Index e = 0; e < E.cols(); ++e) edge = std::max(edge, (V.col(E(0, e)) - V.col(E(1, e))).norm());
  int far = 0, far_coupled = 0;
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = n; b < 2 * n; ++b)
      if ((V.col(a) - V.col(b)).norm() > term.layout_reach() + 2.0 * edge) {
        ++far;
        far_coupled += L.entry(static_cast<int>(3 * b), static_cast<int>(3 * a)) >= 0;
      }
  EXPECT_GT(far, 100);
  EXPECT_EQ(far_coupled, 0);
}

TEST(ContactTerm, ALayoutRebuiltAheadServesTheNextIterates) {
  // The second of two finer cubes slides along the first, 0.5 d̂ above it, in 100 steps of 0.18 d̂: the pairs in
  // range change at many steps. A problem (elasticity and contact) asked for a Hessian at each step rebuilds
  // its layout less than half as often as a layout built for the pairs in range alone would need (counted here
  // by rebuilding one whenever the pairs leave it), and its matrices equal a fresh problem's.
  const double dhat = 0.05;
  const TwoCubes cubes(1.0, Vec3(0.3, 0.2, 1.0 + 0.5 * dhat), 3);
  const VolumeMesh& mesh = cubes.mesh;
  const Eigen::Matrix3Xi& F = cubes.F;
  const Eigen::Index n = mesh.vertex_count() / 2;
  ElasticTerm elastic(mesh, make_material("stable_neo_hookean", {1.0, 10.0}));
  ContactTerm contact(F, EmbeddedPoints::every(2 * n), mesh.vertices, dhat, 1.0);
  Problem p{DofMap(std::vector<std::uint8_t>(3 * mesh.vertex_count(), 0))};
  p.add(elastic);
  p.add(contact);
  Stencil cells, pairs;
  elastic.stencil(flatten(mesh.vertices), cells);
  std::vector<int> numbering(3 * mesh.vertex_count());
  std::iota(numbering.begin(), numbering.end(), 0);
  HessianLayout alone;
  int alone_built = 0;
  Eigen::Matrix3Xd V = mesh.vertices;
  for (int step = 0; step < 100; ++step) {
    V.rightCols(n).colwise() -= Vec3(0.15 * dhat, 0.1 * dhat, 0.0);
    const Eigen::VectorXd x = flatten(V);
    Eigen::VectorXd g;
    HessianMatrix H;
    p.evaluate(x, g, &H, PsdProjection::clamp);
    contact.stencil(x, pairs);
    if (alone_built == 0 || !alone.covers(pairs)) {
      alone = HessianLayout(numbering, static_cast<int>(numbering.size()), {&cells, &pairs});
      ++alone_built;
    }
    if (step % 10 != 9) continue;
    ElasticTerm elastic2(mesh, make_material("stable_neo_hookean", {1.0, 10.0}));
    ContactTerm contact2(F, EmbeddedPoints::every(2 * n), mesh.vertices, dhat, 1.0);
    Problem q{DofMap(std::vector<std::uint8_t>(3 * mesh.vertex_count(), 0))};
    q.add(elastic2);
    q.add(contact2);
    Eigen::VectorXd gq;
    HessianMatrix Hq;
    q.evaluate(x, gq, &Hq, PsdProjection::clamp);
    ASSERT_EQ(Eigen::MatrixXd(H.matrix), Eigen::MatrixXd(Hq.matrix)) << "step " << step;
  }
  std::cout << "layouts: " << p.layouts_built() << " built ahead, " << alone_built << " for the pairs in range alone\n";
  EXPECT_GT(alone_built, 6);
  EXPECT_LE(p.layouts_built() - 1, (alone_built - 1) / 2) << "rebuilds after the first";
}

TEST(ContactTerm, MaxStepKeepsEveryPairApartOnRandomSteps) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.15);
  int unsafe_full_steps = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const TwoCubes cubes(1.0, Vec3(1.1 + 0.1 * trial / 30.0, 0.2 * noise(rng), 0.2 * noise(rng)));
    const ContactTerm term(cubes.F, EmbeddedPoints::every(cubes.mesh.vertices.cols()), cubes.mesh.vertices, 0.05, 1.0);
    const Eigen::VectorXd x = flatten(cubes.mesh.vertices);
    const Eigen::Index n = cubes.mesh.vertex_count() / 2;
    Eigen::Matrix3Xd D(3, 2 * n);
    for (Eigen::Index v = 0; v < 2 * n; ++v)
      D.col(v) = Vec3(v < n ? 1.0 : -1.0, 0, 0) + Vec3(noise(rng), noise(rng), noise(rng));
    const Eigen::VectorXd dx = flatten(D);
    const double alpha = term.max_step(x, dx);
    ASSERT_GT(alpha, 0.0);
    ASSERT_LE(alpha, 1.0);
    const Eigen::Matrix3Xd after = unflatten(x + alpha * dx);
    EXPECT_FALSE(surface_intersects(cubes.F, after)) << "trial " << trial << ", alpha " << alpha;
    EXPECT_GT(surface_min_distance(cubes.F, after), 0.0) << "trial " << trial;
    if (surface_intersects(cubes.F, unflatten(x + dx))) ++unsafe_full_steps;
  }
  EXPECT_GT(unsafe_full_steps, 10);  // the full steps mostly do pass through: the bound has work to do
}

TEST(ContactTerm, KeptCandidatesGiveWhatAFreshTermGivesAlongAWalk) {
  // One term evaluated along a walk of the second cube towards, across and away from the first (moves of
  // 0.2 d̂ to 3 d̂, so the candidates are kept over some moves and found anew over others) against a fresh
  // term at each point: the same energy and gradient bit for bit, and pairs in range at some points.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double dhat = 0.05;
  const TwoCubes cubes(1.0, Vec3(1.2, 0.1, -0.05));
  const ContactTerm walker(cubes.F, EmbeddedPoints::every(cubes.mesh.vertices.cols()), cubes.mesh.vertices, dhat, 1.0);
  Eigen::Matrix3Xd X = cubes.mesh.vertices;
  const Eigen::Index n = X.cols() / 2;
  int with_pairs = 0;
  for (int k = 0; k < 80; ++k) {
    const double size = (k % 4 == 3 ? 3.0 : 0.2) * dhat;
    const Vec3 towards(k < 40 ? -1.0 : 1.0, 0.0, 0.0);  // in, then out
    for (Eigen::Index v = n; v < 2 * n; ++v)
      X.col(v) += size * (0.5 * towards + 0.3 * Vec3(u(rng), u(rng), u(rng)));
    const Eigen::VectorXd x = flatten(X);
    if (surface_min_distance(cubes.F, X) <= 0.0) continue;  // a walk through: skip the contact-free check
    const ContactTerm fresh(cubes.F, EmbeddedPoints::every(cubes.mesh.vertices.cols()), cubes.mesh.vertices, dhat, 1.0);
    Eigen::VectorXd g1 = Eigen::VectorXd::Zero(x.size()), g2 = Eigen::VectorXd::Zero(x.size());
    const double e1 = walker.evaluate(x, &g1, nullptr, PsdProjection::none), e2 = fresh.evaluate(x, &g2, nullptr, PsdProjection::none);
    ASSERT_EQ(e1, e2) << "step " << k;
    ASSERT_TRUE(g1 == g2) << "step " << k;
    if (walker.active_pairs(x) > 0) ++with_pairs;
  }
  EXPECT_GT(with_pairs, 3);
}

TEST(ContactTerm, MaxStepDoesNotLoseAPairEndingInTouchingToTheRoundingOfItsBoxes) {
  // A triangle 0.05 above the top vertex of another comes down to touching it, up to one rounding: at the end
  // its lowest y is the double just above 1, the vertex's is 1. The swept boxes, not grown, do not overlap
  // (the step went all the way, ending 2e-16 apart: seen with the broad phase's d̂ set to 0); grown by d̂
  // they do, and CCD keeps a tenth of the distance.
  Eigen::Matrix3Xd X(3, 6);
  X << 0, -0.5, 0.5, -1, 1, 0,  //
      1, 0.5, 0.5, 1.05, 1.05, 1.05,  //
      0, 0.3, -0.3, -1, -1, 1;
  Eigen::Matrix3Xi F(3, 2);
  F << 0, 3, 1, 5, 2, 4;
  const double drop = 1.05 - std::nextafter(1.0, 2.0);
  ASSERT_GT(1.05 - drop, 1.0);  // the triangle ends above the vertex's y by rounding only
  const ContactTerm term(F, EmbeddedPoints::every(X.cols()), X, 0.01, 1.0);
  const Eigen::VectorXd x = flatten(X);
  Eigen::Matrix3Xd D = Eigen::Matrix3Xd::Zero(3, 6);
  D.row(1).tail(3).setConstant(-drop);
  const Eigen::VectorXd dx = flatten(D);
  const double alpha = term.max_step(x, dx);
  EXPECT_LE(alpha, 0.9 + 1e-9);
  EXPECT_GE(surface_min_distance(F, unflatten(x + alpha * dx)), 0.1 * 0.05 * (1.0 - 1e-9));
}

TEST(PlaneCollider, MatchesFiniteDifferencesAndMaxStepKeepsVerticesAbove) {
  // Four vertices 0.01 to 0.04 above a tilted plane (d̂ = 0.05), one far above it.
  const Vec3 n = Vec3(0.2, 1.0, -0.3).normalized(), p(0.1, -0.2, 0.3);
  Eigen::Matrix3Xd V(3, 5);
  const Vec3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  for (int i = 0; i < 5; ++i) V.col(i) = p + (0.3 * i) * t1 - (0.2 * i) * t2 + (i < 4 ? 0.01 * (i + 1) : 1.0) * n;
  ShapeColliderTerm term(EmbeddedPoints::plain({0, 1, 2, 3, 4}, "test"), plane(p, 7.0 * n), ColliderPose{}, 0.05, 5.0);  // the normal's length does not matter
  Problem problem(DofMap(std::vector<std::uint8_t>(15, 0)));
  problem.add(term);
  const Eigen::VectorXd x = flatten(V);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(term.point_distance(x, i), i < 4 ? 0.01 * (i + 1) : 1.0, 1e-14);
  EXPECT_GT(problem.energy(x), 0.0);
  const FdErrors e = problem_fd_errors(problem, x);
  EXPECT_LE(e.gradient, 1e-6);
  EXPECT_LE(e.hessian, 1e-6);
  // Below the plane: +∞. Random steps: after max_step every vertex keeps a tenth of its distance.
  Eigen::VectorXd below = x;
  below.segment<3>(0) -= 0.02 * n;
  EXPECT_EQ(term.energy(below), INFINITY);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 0.05);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd dx(15);
    for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = g(rng);
    const double alpha = term.max_step(x, dx);
    ASSERT_GT(alpha, 0.0);
    ASSERT_LE(alpha, 1.0);
    for (int i = 0; i < 5; ++i) EXPECT_GE(term.point_distance(x + alpha * dx, i), 0.1 * term.point_distance(x, i) * (1 - 1e-12));
  }
}

TEST(ContactTerm, BadArgumentsThrow) {
  const TwoTets tets(Eigen::Matrix<double, 3, 4>::Random() + Eigen::Matrix<double, 3, 4>::Constant(3.0));
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, -1.0), std::invalid_argument);
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, NAN, 1.0), std::invalid_argument);
  Eigen::Matrix3Xi bad = tets.F;
  bad(0, 0) = 8;
  EXPECT_THROW(ContactTerm(bad, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, 1.0), std::invalid_argument);
  bad(0, 0) = bad(1, 0);
  EXPECT_THROW(ContactTerm(bad, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), plane(Vec3::Zero(), Vec3::Zero()), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({-1}, "test"), plane(Vec3::Zero(), Vec3::UnitY()), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints::plain({0}, "test"), plane(Vec3::Zero(), Vec3::UnitY()), ColliderPose{}, 0.1, INFINITY), std::invalid_argument);
}

TEST(ContactTerm, IpcStiffnessFollowsItsFormula) {
  // κ = 1e11 m̄ / (4 d₀ b''(d₀, ŝ)) / h², d₀ = (1e-8 · diagonal)², b'' written out here.
  const double diagonal = 3.0, dhat = 0.02, mass = 30.0, h = 0.01;
  const double d0 = 1e-16 * diagonal * diagonal, s_hat = dhat * dhat;
  const double b2 = -2.0 * std::log(d0 / s_hat) - 4.0 * (d0 - s_hat) / d0 + (d0 - s_hat) * (d0 - s_hat) / (d0 * d0);
  const double kappa = ipc_barrier_stiffness(diagonal, dhat, mass, h);
  EXPECT_NEAR(kappa, 1e11 * mass / (4.0 * d0 * b2) / (h * h), 1e-12 * kappa);
  EXPECT_NEAR(ipc_barrier_stiffness(diagonal, dhat, 2 * mass, h), 2 * kappa, 1e-12 * kappa);
  EXPECT_NEAR(ipc_barrier_stiffness(diagonal, dhat, mass, 2 * h), kappa / 4, 1e-12 * kappa);
  EXPECT_THROW((void)ipc_barrier_stiffness(0.0, dhat, mass, h), std::invalid_argument);
  EXPECT_THROW((void)ipc_barrier_stiffness(diagonal, dhat, mass, NAN), std::invalid_argument);
}

// ---- dynamics with contact

/// Elasticity, backward Euler with gravity, and optional contact terms over a mesh, free everywhere.
struct Dynamics {
  Dynamics(const VolumeMesh& m, double dt, const Vec3& gravity)
      : elastic(m, make_material("stable_neo_hookean", {2e5, 2e6})),
        dofs(std::vector<std::uint8_t>(3 * static_cast<std::size_t>(m.vertex_count()), 0)),
        inertia(elastic, dofs, lumped_mass(elastic, 100.0), {.dt = dt, .gravity = gravity}),
        problem(dofs),
        dt(dt) {
    problem.add(elastic);
    problem.add(inertia);
  }
  /// One step from (x, v); returns the Newton report.
  NewtonReport step(Eigen::VectorXd& x, Eigen::VectorXd& v) {
    inertia.begin_step(x, v);
    const Eigen::VectorXd x_n = x;  // Newton starts from x_n: the prediction x_n + h v may tunnel through
    auto solver = make_linear_solver({.name = "ldlt"});
    NewtonOptions options;
    options.tolerance = 1e-2;  // absolute: forces here are 1e3 to 1e4 (weights, m v / h), so 1e-6 relative
    const NewtonReport r = newton_solve(problem, x, *solver, options);
    v = (x - x_n) / dt;
    return r;
  }
  ElasticTerm elastic;
  DofMap dofs;
  TimeStepTerm inertia;
  Problem problem;
  double dt;
};

TEST(ContactTerm, NothingInRangeChangesNothingBitForBit) {
  // A cube falling freely (far from the plane; no self pair within d̂): with and without the contact terms
  // the same iterates, bit for bit.
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  std::vector<int> surface(F.data(), F.data() + F.size());
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  Dynamics plain(m, 0.01, Vec3(0, -9.8, 0)), with(m, 0.01, Vec3(0, -9.8, 0));
  ContactTerm self(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, 0.01, 1e3);
  ShapeColliderTerm ground(EmbeddedPoints::plain(surface, "test"), plane(Vec3(0, -10, 0), Vec3(0, 1, 0)), ColliderPose{}, 0.01, 1e3);
  with.problem.add(self);
  with.problem.add(ground);
  Eigen::VectorXd x1 = flatten(m.vertices), v1 = Eigen::VectorXd::Zero(x1.size());
  v1(Eigen::seqN(0, m.vertex_count(), 3)).setConstant(0.3);  // a shear-free drift plus a spin-up below
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) v1[3 * v + 2] += 0.5 * m.vertices(1, v);
  Eigen::VectorXd x2 = x1, v2 = v1;
  for (int s = 0; s < 5; ++s) {
    const NewtonReport a = plain.step(x1, v1), b = with.step(x2, v2);
    EXPECT_EQ(a.iterations, b.iterations);
    ASSERT_EQ(x1, x2) << "step " << s;
    EXPECT_TRUE(self.pairs(x2).empty());
  }
}

TEST(ContactTerm, CrowdingCountsTheSurfaceInRangeOfItselfWithinItsLimit) {
  // A cube's surface ([−1, 1]³, 4 cells a side: edges 0.5): at a d̂ well below its spacing no vertex is
  // within d̂ of a part it does not share; at a d̂ above it, every vertex is (parts two rings away on the same
  // face); with a small limit the search stops.
  const VolumeMesh m = box_tets(4);
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  const Eigen::VectorXd x = flatten(m.vertices);
  const ContactTerm fine(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, 0.05, 1.0);
  const Crowding quiet = fine.crowding(x, 1'000'000);
  EXPECT_TRUE(quiet.complete);
  EXPECT_EQ(quiet.in_range, 0);
  EXPECT_EQ(quiet.pairs, 0u);
  EXPECT_EQ(quiet.min_distance, 0.05);
  EXPECT_EQ(quiet.vertices, 98);  // 6·25 − 12·5 + 8: the 5×5×5 grid's surface
  const ContactTerm coarse(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, 0.6, 1.0);
  const Crowding crowded = coarse.crowding(x, 1'000'000);
  EXPECT_TRUE(crowded.complete);
  EXPECT_EQ(crowded.in_range, crowded.vertices);
  EXPECT_EQ(crowded.pairs, coarse.pairs(x).size());  // what the term itself would act on
  EXPECT_EQ(crowded.min_distance, coarse.min_distance(x));
  EXPECT_LT(crowded.min_distance, 0.5);
  EXPECT_GT(crowded.candidates, crowded.pairs);
  const Crowding cut = coarse.crowding(x, 100);
  EXPECT_FALSE(cut.complete);
  EXPECT_GT(cut.candidates, 100u);
  EXPECT_EQ(cut.in_range, 0);  // not counted past the limit
}

TEST(ContactTerm, ACubeDroppedOnTheGroundComesToRestAboveIt) {
  const VolumeMesh m = box_tets(1);  // [−1, 1]³
  const Eigen::Matrix3Xi F = boundary_triangles(m);
  std::vector<int> surface(F.data(), F.data() + F.size());
  std::sort(surface.begin(), surface.end());
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  const double dhat = 0.02, ground_y = -1.3;
  Dynamics run(m, 0.01, Vec3(0, -9.8, 0));
  ContactTerm self(F, EmbeddedPoints::every(m.vertices.cols()), m.vertices, dhat, 1e8);
  ShapeColliderTerm ground(EmbeddedPoints::plain(surface, "test"), plane(Vec3(0, ground_y, 0), Vec3(0, 1, 0)), ColliderPose{}, dhat, 1e8);
  run.problem.add(self);
  run.problem.add(ground);
  Eigen::VectorXd x = flatten(m.vertices), v = Eigen::VectorXd::Zero(x.size());
  double lowest = INFINITY;
  for (int s = 0; s < 150; ++s) {
    const NewtonReport r = run.step(x, v);
    ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
    for (Eigen::Index i = 0; i < m.vertex_count(); ++i) {
      ASSERT_GT(x[3 * i + 1], ground_y) << "step " << s << ", vertex " << i;
      lowest = std::min(lowest, x[3 * i + 1] - ground_y);
    }
  }
  double bottom = INFINITY;
  for (Eigen::Index i = 0; i < m.vertex_count(); ++i) bottom = std::min(bottom, x[3 * i + 1] - ground_y);
  EXPECT_GT(bottom, 0.0);
  EXPECT_LT(bottom, dhat);                           // resting on the barrier, not floating
  EXPECT_LT(v.cwiseAbs().maxCoeff(), 0.05);          // at rest
  std::cout << "lowest distance above the ground " << lowest << ", at rest " << bottom << "\n";
}

TEST(ContactTerm, TwoCubesThrownAtEachOtherBounceApartWithoutIntersecting) {
  const TwoCubes cubes(1.0, Vec3(1.3, 0.2, 0.1));
  const double dhat = 0.02;
  Dynamics run(cubes.mesh, 0.01, Vec3::Zero());
  ContactTerm self(cubes.F, EmbeddedPoints::every(cubes.mesh.vertices.cols()), cubes.mesh.vertices, dhat, 1e8);
  run.problem.add(self);
  const Eigen::Index n = cubes.mesh.vertex_count() / 2;
  Eigen::VectorXd x = flatten(cubes.mesh.vertices), v = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index i = 0; i < 2 * n; ++i) v[3 * i] = i < n ? 2.0 : -2.0;
  double closest = INFINITY;
  int contact_steps = 0;
  for (int s = 0; s < 40; ++s) {
    const NewtonReport r = run.step(x, v);
    ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
    const Eigen::Matrix3Xd V = unflatten(x);
    ASSERT_FALSE(surface_intersects(cubes.F, V)) << "step " << s;
    const double d = surface_min_distance(cubes.F, V);
    ASSERT_GT(d, 0.0);
    closest = std::min(closest, d);
    if (!self.pairs(x).empty()) ++contact_steps;
  }
  EXPECT_GT(contact_steps, 0);
  EXPECT_LT(closest, dhat);
  // The layout was rebuilt for the pairs within 4 d̂ when the first came in range, and served every step after.
  EXPECT_EQ(run.problem.layouts_built(), 2);
  // Bounced: the cubes' mean velocities now point away from each other.
  const double va = v(Eigen::seqN(0, n, 3)).mean(), vb = v(Eigen::seqN(3 * n, n, 3)).mean();
  EXPECT_LT(va, 0.0);
  EXPECT_GT(vb, 0.0);
  std::cout << "closest approach " << closest << ", steps in contact " << contact_steps << ", velocities " << va
            << " " << vb << "\n";
}

TEST(ContactTerm, ASimulationsGuessDoesNotJumpThroughAContact) {
  // Two cubes 0.3 apart at ±40 m/s with h = 0.01: the inertial prediction x_n + h v overlaps them by 0.5,
  // an intersecting state of finite energy (no pair exactly at distance 0), from which Newton would never
  // separate them. The Simulation bounds the guess by the contact term's CCD, so no step ever intersects.
  const TwoCubes cubes(1.0, Vec3(1.3, 0.1, 0.05));
  SimulationSetup setup;
  setup.mesh = cubes.mesh;
  setup.materials = {make_material("stable_neo_hookean", {2e5, 2e6})};
  setup.density = 100.0;
  setup.integrator = Integrator::backward_euler;
  setup.dt = 0.01;
  setup.newton.tolerance = 1e-2;
  setup.linear.name = "ldlt";
  setup.terms.push_back(std::make_shared<ContactTerm>(cubes.F, EmbeddedPoints::every(cubes.mesh.vertices.cols()), cubes.mesh.vertices, 0.02, 1e8));
  Simulation sim(std::move(setup));
  const Eigen::Index n = cubes.mesh.vertex_count() / 2;
  SimulationState state = sim.state();
  state.aux = Eigen::VectorXd::Zero(state.x.size());
  for (Eigen::Index i = 0; i < 2 * n; ++i) state.aux[3 * i] = i < n ? 40.0 : -40.0;
  sim.restore(state);
  EXPECT_TRUE(surface_intersects(cubes.F, unflatten(state.x + 0.01 * state.aux)));  // the prediction would
  for (int s = 1; s <= 10; ++s) {
    const StepReport r = sim.step(0.01 * s);
    ASSERT_TRUE(r.converged) << "step " << s << ": " << r.failure;
    ASSERT_FALSE(surface_intersects(cubes.F, unflatten(sim.x()))) << "step " << s;
  }
}

// ---- surfaces embedded in a volume (a flesh's render surface): the same pairs on p = W x, derivatives
// through the weights.

/// TwoTets' 8 vertices as points embedded in a volume: two hexes (trilinear weights, 16 vertices) or two
/// tets (barycentric, 8 vertices), one cell around each small tet, the volume then deformed at random so
/// that the map x → p is not affine (hexes).
struct EmbeddedTwoTets {
  Eigen::Matrix3Xd rest;  ///< the volume at rest
  Eigen::MatrixXi vertex;
  Eigen::MatrixXd weight;
  Eigen::VectorXd x;      ///< the volume deformed
  EmbeddedTwoTets(const TwoTets& tets, bool hexes, unsigned seed) {
    const int k = hexes ? 8 : 4;
    rest.resize(3, 2 * k);
    vertex.resize(k, 8);
    weight.resize(k, 8);
    for (int c = 0; c < 2; ++c) {  // cell c around the small tet's vertices 4c … 4c + 3
      const Eigen::Matrix<double, 3, 4> small = tets.V.middleCols<4>(4 * c);
      const Vec3 center = small.rowwise().mean();
      if (hexes) {
        const Vec3 lo = small.rowwise().minCoeff().array() - 0.3;
        const double side = (small.rowwise().maxCoeff() - small.rowwise().minCoeff()).maxCoeff() + 0.6;
        for (int corner = 0; corner < 8; ++corner)
          rest.col(8 * c + corner) = lo + side * Vec3(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
        for (int i = 0; i < 4; ++i) {
          const Vec3 u = (small.col(i) - lo) / side;
          for (int corner = 0; corner < 8; ++corner) {
            vertex(corner, 4 * c + i) = 8 * c + corner;
            weight(corner, 4 * c + i) = ((corner & 1) ? u[0] : 1 - u[0]) * (((corner >> 1) & 1) ? u[1] : 1 - u[1]) *
                                        (((corner >> 2) & 1) ? u[2] : 1 - u[2]);
          }
        }
      } else {
        const Eigen::Matrix<double, 3, 4> big = (2.0 * (small.colwise() - center)).colwise() + center;
        rest.middleCols<4>(4 * c) = big;
        Eigen::Matrix3d edges;
        for (int a = 0; a < 3; ++a) edges.col(a) = big.col(a + 1) - big.col(0);
        for (int i = 0; i < 4; ++i) {
          const Vec3 b = edges.inverse() * (small.col(i) - big.col(0));
          const Eigen::Vector4d w(1 - b.sum(), b[0], b[1], b[2]);
          for (int a = 0; a < 4; ++a) {
            vertex(a, 4 * c + i) = 4 * c + a;
            weight(a, 4 * c + i) = w[a];
          }
        }
      }
    }
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-0.005, 0.005);
    x = flatten(rest);
    for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += u(rng);
  }
};

TEST(ContactTerm, AnEmbeddedSurfaceMatchesFiniteDifferencesThroughItsWeights) {
  Eigen::Matrix<double, 3, 4> B;  // as VertexTriangleAndEdgeEdgePairsMatchFiniteDifferences
  B << 0.5, 0.5, 0.3, 0.8,  //
      -0.3, 0.3, 0.0, 0.0,  //
      0.04, 0.04, 1.0, 1.0;
  for (const bool hexes : {true, false})
    for (unsigned seed : {11u, 12u}) {
      SCOPED_TRACE(hexes ? "hexes" : "tets");
      const TwoTets tets(jitter(B, seed));
      const EmbeddedTwoTets e(tets, hexes, seed);
      ContactTerm term(tets.F, EmbeddedPoints(e.vertex, e.weight, "test", e.rest.cols()), e.rest, 0.1, 10.0);
      const Eigen::Matrix3Xd P = term.positions(e.x);
      const auto pairs = term.pairs(e.x);
      EXPECT_TRUE(has_kind(pairs, Kind::point_triangle));
      EXPECT_TRUE(has_kind(pairs, Kind::edge_edge));
      Problem problem(DofMap(std::vector<std::uint8_t>(static_cast<std::size_t>(e.x.size()), 0)));
      problem.add(term);
      EXPECT_GT(problem.energy(e.x), 0.0);
      const FdErrors fd = problem_fd_errors(problem, e.x);
      EXPECT_LE(fd.gradient, 1e-6);
      EXPECT_LE(fd.hessian, 1e-6);
      // The projected Hessian (pairs projected before the chain rule) is PSD.
      const Eigen::MatrixXd Hp = assembled(term, e.x, PsdProjection::clamp).first;
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hp).eigenvalues().minCoeff(), -1e-9 * Hp.norm());
      // The same surface given directly at the points p = W x: the same energy, pairs, max_step, and the
      // gradient pulled back by Wᵀ.
      Eigen::Matrix3Xd point_rest(3, 8);
      for (int i = 0; i < 8; ++i) {
        point_rest.col(i).setZero();
        for (Eigen::Index c = 0; c < e.vertex.rows(); ++c) point_rest.col(i) += e.weight(c, i) * e.rest.col(e.vertex(c, i));
      }
      ContactTerm direct(tets.F, EmbeddedPoints::every(point_rest.cols()), point_rest, 0.1, 10.0);
      EXPECT_NEAR(term.energy(e.x), direct.energy(flatten(P)), 1e-12 * direct.energy(flatten(P)));
      EXPECT_EQ(term.pairs(e.x).size(), direct.pairs(flatten(P)).size());
      const Eigen::VectorXd gp = assembled(direct, flatten(P), PsdProjection::none).second;
      Eigen::VectorXd gx = Eigen::VectorXd::Zero(e.x.size());
      for (int i = 0; i < 8; ++i)
        for (Eigen::Index c = 0; c < e.vertex.rows(); ++c) gx.segment<3>(3 * e.vertex(c, i)) += e.weight(c, i) * gp.segment<3>(3 * i);
      EXPECT_LE((assembled(term, e.x, PsdProjection::none).second - gx).norm(), 1e-12 * gx.norm());
      std::mt19937_64 rng(seed);
      std::normal_distribution<double> g(0.0, 0.3);
      for (int trial = 0; trial < 10; ++trial) {
        Eigen::VectorXd dx(e.x.size());
        for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = g(rng);
        const double t = term.max_step(e.x, dx);
        EXPECT_EQ(t, direct.max_step(flatten(P), flatten(term.positions(dx))));
        EXPECT_GT(t, 0.0);
        EXPECT_FALSE(surface_intersects(tets.F, term.positions(e.x + t * dx))) << "trial " << trial;
      }
    }
}

// Plain points keep their own path (plain gathers and scatters); the same points taken through weights (one
// of 1, one of 0) agree with it up to the last bits (a pair Hessian's blocks are added in the other orientation
// where the volume ids are in the other order, and its symmetry holds to rounding only).
TEST(ContactTerm, IdentityWeightsGiveTheDirectTerm) {
  Eigen::Matrix<double, 3, 4> B;
  B << 0.2, 0.8, 0.3, 0.7,     //
      -0.02, -0.01, -0.4, -0.4,  //
      0.05, 0.05, 1.0, 1.0;
  const TwoTets tets(jitter(B, 4));
  ContactTerm direct(tets.F, EmbeddedPoints::every(tets.V.cols()), tets.V, 0.1, 10.0);
  ContactTerm embedded(tets.F, identity_through_weights(8), tets.V, 0.1, 10.0);
  const Eigen::VectorXd x = flatten(tets.V);
  EXPECT_EQ(direct.energy(x), embedded.energy(x));
  for (const PsdProjection p : {PsdProjection::none, PsdProjection::clamp}) {
    const auto [Hd, gd] = assembled(direct, x, p);
    const auto [He, ge] = assembled(embedded, x, p);
    EXPECT_EQ(gd, ge);
    EXPECT_LE((Hd - He).norm(), 1e-14 * Hd.norm());
    EXPECT_GT(Hd.norm(), 0.0);
  }
}

TEST(ContactTerm, BadEmbeddingsThrow) {
  const TwoTets tets(Eigen::Matrix<double, 3, 4>::Identity() * 0.5);
  const Eigen::MatrixXi ids = Eigen::RowVectorXi::LinSpaced(8, 0, 7);
  const Eigen::MatrixXd ones = Eigen::RowVectorXd::Ones(8);
  EXPECT_NO_THROW(ContactTerm(tets.F, EmbeddedPoints(ids, ones, "test", tets.V.cols()), tets.V, 0.1, 1.0));
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints(ids, Eigen::MatrixXd::Ones(2, 8), "test", tets.V.cols()), tets.V, 0.1, 1.0), std::invalid_argument);  // shapes
  Eigen::MatrixXi far = ids;
  far(0, 3) = 8;  // beyond the volume's 8 vertices
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints(far, ones, "test", tets.V.cols()), tets.V, 0.1, 1.0), std::invalid_argument);
  Eigen::MatrixXd nan = ones;
  nan(0, 2) = NAN;
  EXPECT_THROW(ContactTerm(tets.F, EmbeddedPoints(ids, nan, "test", tets.V.cols()), tets.V, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(ids, nan, "test", -1), plane(Vec3::Zero(), Vec3::UnitY()), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(ids, Eigen::MatrixXd::Ones(1, 7), "test", -1), plane(Vec3::Zero(), Vec3::UnitY()), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
  Eigen::MatrixXi negative = ids;
  negative(0, 1) = -1;
  EXPECT_THROW(ShapeColliderTerm(EmbeddedPoints(negative, ones, "test", -1), plane(Vec3::Zero(), Vec3::UnitY()), ColliderPose{}, 0.1, 1.0), std::invalid_argument);
}

TEST(PlaneCollider, EmbeddedPointsMatchFiniteDifferencesThroughTheirWeights) {
  // A cube's 8 vertices (deformed at random) and 5 points in it by trilinear weights, 0.01 to 0.04 above a
  // tilted plane (d̂ = 0.05) or far above it.
  const Vec3 n = Vec3(0.2, 1.0, -0.3).normalized(), p(0.1, -0.2, 0.3);
  const Vec3 t1 = n.unitOrthogonal(), t2 = n.cross(t1);
  Eigen::Matrix3Xd cube(3, 8);
  for (int c = 0; c < 8; ++c)
    cube.col(c) = p - 0.5 * n + ((c & 1) ? 1.5 : -0.5) * t1 + (((c >> 1) & 1) ? 1.5 : -0.5) * t2 + (((c >> 2) & 1) ? 2.0 : 0.0) * n;
  Eigen::MatrixXi vertex(8, 5);
  Eigen::MatrixXd weight(8, 5);
  for (int i = 0; i < 5; ++i) {
    const Vec3 u(0.1 + 0.15 * i, 0.6 - 0.1 * i, (0.5 + (i < 4 ? 0.01 * (i + 1) : 1.0)) / 2.0);
    for (int c = 0; c < 8; ++c) {
      vertex(c, i) = c;
      weight(c, i) = ((c & 1) ? u[0] : 1 - u[0]) * (((c >> 1) & 1) ? u[1] : 1 - u[1]) * (((c >> 2) & 1) ? u[2] : 1 - u[2]);
    }
  }
  ShapeColliderTerm term(EmbeddedPoints(vertex, weight, "test", -1), plane(p, n), ColliderPose{}, 0.05, 5.0);
  const Eigen::VectorXd x = flatten(cube);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(term.point_distance(x, i), i < 4 ? 0.01 * (i + 1) : 1.0, 1e-14);
  EXPECT_EQ(term.active_pairs(x), 4);
  EXPECT_NEAR(term.min_distance(x), 0.01, 1e-14);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.002, 0.002);
  Eigen::VectorXd y = x;
  for (Eigen::Index i = 0; i < y.size(); ++i) y[i] += u(rng);
  Problem problem(DofMap(std::vector<std::uint8_t>(24, 0)));
  problem.add(term);
  EXPECT_GT(problem.energy(y), 0.0);
  const FdErrors e = problem_fd_errors(problem, y);
  EXPECT_LE(e.gradient, 1e-6);
  EXPECT_LE(e.hessian, 1e-6);
  const Eigen::MatrixXd Hp = assembled(term, y, PsdProjection::clamp).first;
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hp).eigenvalues().minCoeff(), -1e-9 * Hp.norm());
  std::normal_distribution<double> g(0.0, 0.05);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd dx(24);
    for (Eigen::Index i = 0; i < dx.size(); ++i) dx[i] = g(rng);
    const double alpha = term.max_step(y, dx);
    ASSERT_GT(alpha, 0.0);
    for (int i = 0; i < 5; ++i) EXPECT_GE(term.point_distance(y + alpha * dx, i), 0.1 * term.point_distance(y, i) * (1 - 1e-9));
  }
}

// Every contact term reports its statistics through the Term interface: its active pairs and their smallest
// distance at the state asked, and what it counted since it last reported (then counted anew); other terms
// report nothing.
TEST(ContactStatistics, EveryContactTermReportsThroughTheTermInterface) {
  // Two unit cubes 0.03 apart along x, the ground 0.02 below them, a sphere 0.04 from the right cube's far
  // top front corner (along the corner's diagonal).
  const TwoCubes cubes(1.0, Vec3(1.03, 0.0, 0.0));
  const Eigen::Matrix3Xd& X = cubes.mesh.vertices;
  const double bottom = X.row(1).minCoeff();
  const Vec3 corner = X.rowwise().maxCoeff(), centre = corner + 0.54 * Vec3::Ones().normalized();
  const EmbeddedPoints every = EmbeddedPoints::every(X.cols());
  ContactTerm self(cubes.F, every, X, 0.05, 1.0);
  ShapeColliderTerm ground(every, plane(Vec3(0, bottom - 0.02, 0), Vec3::UnitY()), ColliderPose{}, 0.05, 1.0);
  ShapeColliderTerm ball(every, {ColliderShape::Kind::sphere, centre, Vec3::Zero(), 0.5}, ColliderPose{}, 0.05, 1.0);
  const Eigen::VectorXd x = flatten(X);
  for (Term* t : std::initializer_list<Term*>{&self, &ground, &ball}) EXPECT_TRUE(t->reports_contact());
  ContactStatistics s;
  self.report_contact(x, s);
  EXPECT_EQ(s.pairs, self.active_pairs(x));
  EXPECT_GT(s.pairs, 0);
  EXPECT_NEAR(s.min_distance, 0.03, 1e-12);
  const int self_pairs = s.pairs;
  ground.report_contact(x, s);
  EXPECT_EQ(s.pairs - self_pairs, 8);  // the bottom corners of both cubes, 0.02 above the ground
  EXPECT_NEAR(s.min_distance, 0.02, 1e-12);
  // The counters: a step bound asked twice, reported once, then nothing more.
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(x.size());
  for (Eigen::Index v = 0; v < X.cols(); ++v) dx[3 * v + 1] = -0.1;
  (void)ground.max_step(x, dx);
  (void)ground.max_step(x, dx);
  ContactStatistics again;
  ground.report_contact(x, again);
  EXPECT_EQ(again.ccd_calls, 2);
  EXPECT_EQ(again.ccd_tests, 2 * X.cols());
  ContactStatistics after;
  ground.report_contact(x, after);
  EXPECT_EQ(after.ccd_calls, 0);
  ContactStatistics ball_only;
  ball.report_contact(x, ball_only);
  EXPECT_EQ(ball_only.pairs, 1);  // that corner alone
  EXPECT_NEAR(ball_only.min_distance, 0.04, 1e-12);
  // A term that is not a contact term adds nothing.
  AttachmentTerm spring({0}, Eigen::VectorXd::Ones(1), [&](double, Eigen::Matrix3Xd& out) { out = X.leftCols(1); });
  EXPECT_FALSE(spring.reports_contact());
  ContactStatistics none;
  spring.report_contact(x, none);
  EXPECT_EQ(none.pairs, 0);
  EXPECT_TRUE(std::isnan(none.min_distance));
}

}  // namespace
}  // namespace snh
