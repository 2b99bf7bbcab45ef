// The broad phase against a brute-force O(n²) list of the same box test on random triangle meshes (the
// same pairs exactly, in sorted order), its conservativeness against exact distances, and its bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "snh/contact/broad_phase.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {
namespace {

struct Mesh {
  Eigen::Matrix3Xd V0, V1;
  Eigen::Matrix3Xi F;
};

/// n vertices in the unit cube, m triangles on random distinct vertices (so triangles share vertices and
/// edges at random), each vertex moved by up to `motion` in each coordinate.
Mesh random_mesh(std::mt19937_64& rng, int n, int m, double motion) {
  std::uniform_real_distribution<double> u(0, 1), d(-motion, motion);
  std::uniform_int_distribution<int> pick(0, n - 1);
  Mesh mesh{Eigen::Matrix3Xd(3, n), Eigen::Matrix3Xd(3, n), Eigen::Matrix3Xi(3, m)};
  for (int v = 0; v < n; ++v) {
    mesh.V0.col(v) << u(rng), u(rng), u(rng);
    mesh.V1.col(v) = mesh.V0.col(v) + Eigen::Vector3d(d(rng), d(rng), d(rng));
  }
  for (int f = 0; f < m; ++f) {
    int a = pick(rng), b = pick(rng), c = pick(rng);
    while (b == a) b = pick(rng);
    while (c == a || c == b) c = pick(rng);
    mesh.F.col(f) << a, b, c;
  }
  return mesh;
}

/// The box of some vertices over both positions, grown by r: written out coordinate by coordinate.
std::array<double, 6> box(const Mesh& mesh, std::initializer_list<int> ids, double r) {
  std::array<double, 6> b = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
  for (int v : ids)
    for (int k = 0; k < 3; ++k) {
      b[k] = std::min({b[k], mesh.V0(k, v), mesh.V1(k, v)});
      b[3 + k] = std::max({b[3 + k], mesh.V0(k, v), mesh.V1(k, v)});
    }
  for (int k = 0; k < 3; ++k) b[k] -= r, b[3 + k] += r;
  return b;
}
bool boxes_overlap(const std::array<double, 6>& a, const std::array<double, 6>& b) {
  for (int k = 0; k < 3; ++k)
    if (a[k] > b[3 + k] || b[k] > a[3 + k]) return false;
  return true;
}

Candidates brute_force(const Mesh& mesh, const Eigen::Matrix2Xi& E, double dhat) {
  Candidates c;
  for (int v = 0; v < mesh.V0.cols(); ++v)
    for (int f = 0; f < mesh.F.cols(); ++f) {
      if (mesh.F(0, f) == v || mesh.F(1, f) == v || mesh.F(2, f) == v) continue;
      if (boxes_overlap(box(mesh, {v}, dhat / 2), box(mesh, {mesh.F(0, f), mesh.F(1, f), mesh.F(2, f)}, dhat / 2)))
        c.vertex_triangle.push_back({v, f});
    }
  for (int a = 0; a < E.cols(); ++a)
    for (int b = a + 1; b < E.cols(); ++b) {
      if (E(0, a) == E(0, b) || E(0, a) == E(1, b) || E(1, a) == E(0, b) || E(1, a) == E(1, b)) continue;
      if (boxes_overlap(box(mesh, {E(0, a), E(1, a)}, dhat / 2), box(mesh, {E(0, b), E(1, b)}, dhat / 2)))
        c.edge_edge.push_back({a, b});
    }
  return c;
}

TEST(BroadPhase, SurfaceEdges) {
  Eigen::Matrix3Xi F(3, 4);  // a tetrahedron's surface: 6 edges
  F << 0, 0, 0, 1, 1, 3, 2, 2, 2, 1, 3, 3;
  const Eigen::Matrix2Xi E = surface_edges(F);
  Eigen::Matrix2Xi expected(2, 6);
  expected << 0, 0, 0, 1, 1, 2, 1, 2, 3, 2, 3, 3;
  EXPECT_EQ(E, expected);
}

TEST(BroadPhase, SameAsBruteForceOnRandomMeshes) {
  std::mt19937_64 rng(41);
  std::size_t total_vt = 0, total_ee = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 20 + 10 * trial, m = 2 * n;
    const Mesh mesh = random_mesh(rng, n, m, trial % 3 == 0 ? 0.0 : 0.05 * (trial % 3));
    const Eigen::Matrix2Xi E = surface_edges(mesh.F);
    for (double dhat : {0.0, 0.02, 0.1}) {
      const Candidates got = broad_phase(mesh.V0, mesh.V1, mesh.F, E, dhat);
      const Candidates want = brute_force(mesh, E, dhat);
      EXPECT_EQ(got.vertex_triangle, want.vertex_triangle) << "trial " << trial << " dhat " << dhat;
      EXPECT_EQ(got.edge_edge, want.edge_edge) << "trial " << trial << " dhat " << dhat;
      total_vt += want.vertex_triangle.size();
      total_ee += want.edge_edge.size();
      // Some pairs, but not all: the box test prunes.
      EXPECT_LT(want.edge_edge.size(), std::size_t(E.cols()) * (E.cols() - 1) / 2);
    }
  }
  EXPECT_GT(total_vt, 1000u);
  EXPECT_GT(total_ee, 1000u);
}

/// A crumpled sheet of n × n vertices (small triangles, two per square, folded over itself so that distant
/// parts lie close), a few of its vertices swept far (boxes over many of the grid's cells, tested against
/// all) and the rest by a little: the grid search finds the brute force's pairs exactly.
TEST(BroadPhase, SameAsBruteForceOnAFineFoldedSheetWithAFewLongSweeps) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  const int n = 24;
  Mesh mesh{Eigen::Matrix3Xd(3, n * n), Eigen::Matrix3Xd(3, n * n), Eigen::Matrix3Xi(3, 2 * (n - 1) * (n - 1))};
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = static_cast<double>(i) / (n - 1), v = static_cast<double>(j) / (n - 1);
      // folded along u = 1/2 (the second half laid back over the first, 0.03 above it) and waved
      const double x = u < 0.5 ? u : 1.0 - u, y = (u < 0.5 ? 0.0 : 0.03) + 0.01 * std::sin(9.0 * v);
      mesh.V0.col(i + n * j) << x + jitter(rng), y + jitter(rng), v + jitter(rng);
      mesh.V1.col(i + n * j) = mesh.V0.col(i + n * j) + Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
    }
  for (const int far : {5, 100, 333, 470}) mesh.V1.col(far) += Eigen::Vector3d(0.3, -0.4, 0.5);  // long sweeps
  int f = 0;
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = i + n * j;
      mesh.F.col(f++) << a, a + 1, a + n + 1;
      mesh.F.col(f++) << a, a + n + 1, a + n;
    }
  const Eigen::Matrix2Xi E = surface_edges(mesh.F);
  for (double dhat : {0.0, 0.01, 0.05}) {
    const Candidates got = broad_phase(mesh.V0, mesh.V1, mesh.F, E, dhat);
    const Candidates want = brute_force(mesh, E, dhat);
    EXPECT_EQ(got.vertex_triangle, want.vertex_triangle) << "dhat " << dhat;
    EXPECT_EQ(got.edge_edge, want.edge_edge) << "dhat " << dhat;
    EXPECT_GT(want.vertex_triangle.size(), 1000u);  // the folded halves do meet in boxes
  }
}

/// Every pair within d̂ (static positions) is a candidate.
TEST(BroadPhase, EveryPairWithinDhatIsACandidate) {
  std::mt19937_64 rng(42);
  const Mesh mesh = random_mesh(rng, 150, 300, 0.0);
  const Eigen::Matrix2Xi E = surface_edges(mesh.F);
  const double dhat = 0.05;
  const Candidates got = broad_phase(mesh.V0, mesh.V0, mesh.F, E, dhat);
  int close = 0;
  for (int v = 0; v < mesh.V0.cols(); ++v)
    for (int f = 0; f < mesh.F.cols(); ++f) {
      const Eigen::Vector3i t = mesh.F.col(f);
      if ((t.array() == v).any()) continue;
      if (point_triangle_distance(mesh.V0.col(v), mesh.V0.col(t[0]), mesh.V0.col(t[1]), mesh.V0.col(t[2])) <
          dhat * dhat) {
        ++close;
        EXPECT_TRUE(std::binary_search(got.vertex_triangle.begin(), got.vertex_triangle.end(), std::array<int, 2>{v, f}))
            << v << " " << f;
      }
    }
  for (int a = 0; a < E.cols(); ++a)
    for (int b = a + 1; b < E.cols(); ++b) {
      if (E(0, a) == E(0, b) || E(0, a) == E(1, b) || E(1, a) == E(0, b) || E(1, a) == E(1, b)) continue;
      if (edge_edge_distance(mesh.V0.col(E(0, a)), mesh.V0.col(E(1, a)), mesh.V0.col(E(0, b)), mesh.V0.col(E(1, b))) <
          dhat * dhat) {
        ++close;
        EXPECT_TRUE(std::binary_search(got.edge_edge.begin(), got.edge_edge.end(), std::array<int, 2>{a, b}))
            << a << " " << b;
      }
    }
  EXPECT_GT(close, 100);
}

/// With a limit the search stops past it (complete false), and below it finds the same pairs as without.
TEST(BroadPhase, StopsPastItsLimit) {
  std::mt19937_64 rng(44);
  Mesh mesh = random_mesh(rng, 200, 400, 0.05);
  mesh.V1.col(7) += Eigen::Vector3d(0.6, 0.6, 0.6);  // oversize boxes too (each pair of them met once)
  mesh.V1.col(8) -= Eigen::Vector3d(0.6, 0.6, 0.6);
  const Eigen::Matrix2Xi E = surface_edges(mesh.F);
  const Candidates all = broad_phase(mesh.V0, mesh.V1, mesh.F, E, 0.1);
  const std::size_t n = all.vertex_triangle.size() + all.edge_edge.size();
  ASSERT_TRUE(all.complete);
  ASSERT_GT(n, 1000u);
  const Candidates exact = broad_phase(mesh.V0, mesh.V1, mesh.F, E, 0.1, n);
  EXPECT_TRUE(exact.complete);
  EXPECT_EQ(exact.vertex_triangle, all.vertex_triangle);
  EXPECT_EQ(exact.edge_edge, all.edge_edge);
  for (const std::size_t limit : {std::size_t{0}, std::size_t{10}, n / 2, n - 1}) {
    const Candidates cut = broad_phase(mesh.V0, mesh.V1, mesh.F, E, 0.1, limit);
    EXPECT_FALSE(cut.complete) << limit;
    EXPECT_GT(cut.vertex_triangle.size() + cut.edge_edge.size(), limit);
    EXPECT_LE(cut.vertex_triangle.size() + cut.edge_edge.size(), n);
  }
}

TEST(BroadPhase, BadInputThrows) {
  std::mt19937_64 rng(43);
  Mesh mesh = random_mesh(rng, 10, 10, 0.0);
  const Eigen::Matrix2Xi E = surface_edges(mesh.F);
  EXPECT_THROW((void)broad_phase(mesh.V0, mesh.V1.leftCols(9), mesh.F, E, 0.1), std::invalid_argument);
  EXPECT_THROW((void)broad_phase(mesh.V0, mesh.V1, mesh.F, E, -1.0), std::invalid_argument);
  Eigen::Matrix3Xi bad = mesh.F;
  bad(1, 3) = 10;
  EXPECT_THROW((void)broad_phase(mesh.V0, mesh.V1, bad, E, 0.1), std::invalid_argument);
  mesh.V1(2, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)broad_phase(mesh.V0, mesh.V1, mesh.F, E, 0.1), std::invalid_argument);
  // Empty input: no candidates.
  const Candidates none = broad_phase(Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xi(3, 0),
                                      Eigen::Matrix2Xi(2, 0), 0.1);
  EXPECT_TRUE(none.vertex_triangle.empty() && none.edge_edge.empty());
}

}  // namespace
}  // namespace snh::contact
