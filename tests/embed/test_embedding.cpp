// Points embedded in hex lattices (trilinear) and tet meshes (barycentric), embed/.
#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <Eigen/Geometry>

#include "embed/surfaces.hpp"
#include "snh/embed/embedding.hpp"
#include "snh/embed/lattice.hpp"
#include "snh/mesh/box.hpp"

namespace snh {
namespace {

/// The largest distance between corresponding columns, over the points' scale (at least 1).
double relative_error(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  EXPECT_EQ(a.cols(), b.cols());
  const double scale = std::max(1.0, b.cwiseAbs().maxCoeff());
  return (a - b).colwise().norm().maxCoeff() / scale;
}

/// An affine map with a positive determinant, and its shift.
struct Affine {
  Eigen::Matrix3d A;
  Eigen::Vector3d b;
  [[nodiscard]] Eigen::Matrix3Xd operator()(const Eigen::Matrix3Xd& X) const { return (A * X).colwise() + b; }
};
const Affine kAffine{(Eigen::Matrix3d() << 1.3, 0.2, -0.4, 0.1, 0.8, 0.3, -0.2, 0.5, 1.7).finished(),
                     Eigen::Vector3d(0.7, -2.5, 4.0)};

/// The message of the std::invalid_argument f throws, or "(no exception)".
template <class Fn>
std::string message_of(Fn&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no exception)";
}

void check_weights(const Embedding& e, int k) {
  ASSERT_EQ(e.vertex.rows(), k);
  ASSERT_EQ(e.weight.rows(), k);
  ASSERT_EQ(e.vertex.cols(), static_cast<Eigen::Index>(e.cell.size()));
  for (Eigen::Index p = 0; p < e.weight.cols(); ++p) {
    EXPECT_NEAR(e.weight.col(p).sum(), 1.0, 1e-14) << "point " << p;
    EXPECT_GE(e.weight.col(p).minCoeff(), -1e-12) << "point " << p;
  }
}

// ---------------------------------------------------------------------------------------------------------
// Lattices

TEST(EmbedLattice, VerticesAndRandomPointsReproduceAndFollowAffineMaps) {
  const test::Surface s = test::icosphere(3, 1.5, Eigen::Vector3d(3.0, -1.0, 0.25));
  const Lattice L = lattice_for_surface(s.V, s.F, 10);
  const Eigen::Matrix3Xd& X = L.mesh.vertices;
  // The lattice's own vertices.
  const Embedding ev = embed_in_lattice(L, X);
  check_weights(ev, 8);
  EXPECT_LT(relative_error(ev.apply(X), X), 1e-12);
  EXPECT_LT(relative_error(ev.apply(kAffine(X)), kAffine(X)), 1e-12);
  // Random points in every cell, each found in its own cell.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(0.001, 0.999);
  Eigen::Matrix3Xd P(3, 4 * L.mesh.cell_count());
  std::vector<int> expected(static_cast<std::size_t>(P.cols()));
  for (Eigen::Index c = 0, p = 0; c < L.mesh.cell_count(); ++c)
    for (int r = 0; r < 4; ++r, ++p) {
      const Eigen::Vector3d lo = X.col(L.mesh.cells(0, c));
      P.col(p) = lo + L.spacing * Eigen::Vector3d(u(rng), u(rng), u(rng));
      expected[static_cast<std::size_t>(p)] = static_cast<int>(c);
    }
  const Embedding e = embed_in_lattice(L, P);
  check_weights(e, 8);
  EXPECT_EQ(e.cell, expected);
  for (Eigen::Index p = 0; p < P.cols(); ++p)
    for (int a = 0; a < 8; ++a) EXPECT_EQ(e.vertex(a, p), L.mesh.cells(a, e.cell[static_cast<std::size_t>(p)]));
  EXPECT_LT(relative_error(e.apply(X), P), 1e-12);
  // Trilinear weights reproduce affine fields exactly: the points follow an affine map of the vertices.
  const Eigen::Matrix3Xd Y = kAffine(X);
  EXPECT_LT(relative_error(e.apply(Y), kAffine(P)), 1e-12);
  // The flat overload (x, y, z of each vertex in turn) gives the same points.
  const Eigen::VectorXd y = Eigen::Map<const Eigen::VectorXd>(Y.data(), Y.size());
  EXPECT_EQ(e.apply(y), e.apply(Y));
}

TEST(EmbedLattice, SphereSurfaceVerticesReproduce) {
  const test::Surface s = test::icosphere(4, 0.8, Eigen::Vector3d(-0.3, 0.6, 0.1));
  const Lattice L = lattice_for_surface(s.V, s.F, 8);
  const Embedding e = embed_in_lattice(L, s.V);
  check_weights(e, 8);
  EXPECT_LT(relative_error(e.apply(L.mesh.vertices), s.V), 1e-12);
  EXPECT_LT(relative_error(e.apply(kAffine(L.mesh.vertices)), kAffine(s.V)), 1e-12);
}

TEST(EmbedLattice, PointOnAFaceFindsTheKeptNeighbour) {
  // An L-shaped solid: a kept cube whose +x neighbour is not kept; a point on their shared face lies in the
  // kept one whichever way floor() rounds.
  const test::Surface s = test::box_solid(4, [](int i, int j, int) { return i < 2 || j < 2; },
                                          Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.013, 0.021, -0.007));
  const Lattice L = lattice_for_surface(s.V, s.F, 9);
  int found = 0;
  for (int k = 0; k < L.dims.z(); ++k)
    for (int j = 0; j < L.dims.y(); ++j)
      for (int i = 0; i + 1 < L.dims.x(); ++i) {
        const int here = L.cell_at[static_cast<std::size_t>(L.cube_index(i, j, k))];
        if (here < 0 || L.cell_at[static_cast<std::size_t>(L.cube_index(i + 1, j, k))] >= 0) continue;
        ++found;
        for (const double nudge : {-1e-9, 0.0, 1e-9}) {
          const Eigen::Matrix3Xd p = L.origin + L.spacing * Eigen::Vector3d(i + 1 + nudge, j + 0.3, k + 0.6);
          const Embedding e = embed_in_lattice(L, p);
          EXPECT_EQ(e.cell[0], here);
          EXPECT_LT(relative_error(e.apply(L.mesh.vertices), p), 1e-12);
        }
      }
  EXPECT_GT(found, 0);
}

TEST(EmbedLattice, PointsOutsideThrowNamingThePoint) {
  const test::Surface s = test::box_solid(4, [](int i, int j, int) { return i < 2 || j < 2; });
  const Lattice L = lattice_for_surface(s.V, s.F, 8);
  Eigen::Matrix3Xd P(3, 4);
  P << 0.1, -0.5, -0.9, 50.0,  //
      0.2, -0.5, 0.9, 0.0,     //
      0.3, 0.5, 0.0, 0.0;
  const std::string far = message_of([&] { (void)embed_in_lattice(L, P); });
  EXPECT_EQ(far, "point 3 (50, 0, 0) lies in no cell of the lattice");
  // In the grid but in the notch, far from any kept cube.
  P.col(3) = Eigen::Vector3d(0.75, 0.75, 0.0);
  EXPECT_EQ(message_of([&] { (void)embed_in_lattice(L, P); }), "point 3 (0.75, 0.75, 0) lies in no cell of the lattice");
  P(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message_of([&] { (void)embed_in_lattice(L, P); }).find("point 2"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------
// Tets

TEST(EmbedTets, RandomPointsReproduceAndFollowAffineMaps) {
  for (const TetSplit split : {TetSplit::paper, TetSplit::mirrored}) {
    VolumeMesh m = box_tets(6, split);
    m.vertices = kAffine(m.vertices);  // a sheared box, off the axes
    std::mt19937 rng(23);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd Q(3, 2000);
    for (Eigen::Index p = 0; p < Q.cols(); ++p) Q.col(p) = Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Matrix3Xd P = kAffine(Q);
    const Embedding e = embed_in_tets(m, P);
    check_weights(e, 4);
    for (Eigen::Index p = 0; p < P.cols(); ++p)
      EXPECT_EQ(e.vertex.col(p), m.cells.col(e.cell[static_cast<std::size_t>(p)]));
    EXPECT_LT(relative_error(e.apply(m.vertices), P), 1e-12);
    const Affine g{Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix() * 2.0,
                   Eigen::Vector3d(-1.0, 0.5, 0.25)};
    EXPECT_LT(relative_error(e.apply(g(m.vertices)), g(P)), 1e-12);
    const Eigen::Matrix3Xd Y = g(m.vertices);
    EXPECT_EQ(e.apply(Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(Y.data(), Y.size()))), e.apply(Y));
  }
}

TEST(EmbedTets, VerticesGetWeightExactlyOne) {
  VolumeMesh m = box_tets(4);
  m.vertices = kAffine(m.vertices);
  const Embedding e = embed_in_tets(m, m.vertices);
  check_weights(e, 4);
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) {
    int hits = 0;
    for (int a = 0; a < 4; ++a) {
      if (e.vertex(a, v) == v) {
        ++hits;
        EXPECT_EQ(e.weight(a, v), 1.0);
      } else {
        EXPECT_EQ(e.weight(a, v), 0.0);
      }
    }
    EXPECT_EQ(hits, 1) << "vertex " << v;
  }
  EXPECT_EQ(e.apply(m.vertices), m.vertices);
}

TEST(EmbedTets, PointsOnSharedFacesTakeTheBestTet) {
  // Centres of interior faces and edges of the lattice: on several tets; the chosen tet holds the point
  // (smallest coordinate ≥ 0 to rounding) and reproduces it.
  const VolumeMesh m = box_tets(3);
  Eigen::Matrix3Xd P(3, 3);
  P << 0.0, -1.0 / 3.0, 1.0 / 3.0,  //
      0.0, 0.0, -1.0 / 3.0,         //
      0.0, 0.5, 0.1;
  const Embedding e = embed_in_tets(m, P);
  check_weights(e, 4);
  EXPECT_LT(relative_error(e.apply(m.vertices), P), 1e-14);
}

TEST(EmbedTets, JustOutsideIsClampedFarOutsideThrows) {
  const VolumeMesh m = box_tets(5);
  const double diagonal = std::sqrt(12.0);
  Eigen::Matrix3Xd P(3, 3);
  P.col(0) = Eigen::Vector3d(1.0 + 1e-7 * diagonal, 0.1, -0.3);  // off the lattice's planes (0.4 apart)
  P.col(1) = Eigen::Vector3d(0.3, 0.1, 1.0 + 3e-7 * diagonal);
  P.col(2) = Eigen::Vector3d(-1.0 - 5e-7 * diagonal, -0.5, 0.9);
  const Embedding e = embed_in_tets(m, P);
  check_weights(e, 4);
  for (Eigen::Index p = 0; p < P.cols(); ++p) EXPECT_GE(e.weight.col(p).minCoeff(), 0.0);
  const Eigen::Matrix3Xd x = e.apply(m.vertices);
  EXPECT_NEAR(x(0, 0), 1.0, 1e-14);  // clamped onto the face x = 1
  EXPECT_NEAR(x(2, 1), 1.0, 1e-14);
  EXPECT_NEAR(x(0, 2), -1.0, 1e-14);
  EXPECT_LT(relative_error(x, P), 1e-6 * diagonal);
  P(2, 1) = 1.0 + 1e-4;  // beyond the tolerance
  EXPECT_EQ(message_of([&] { (void)embed_in_tets(m, P); }), "point 1 (0.3, 0.1, 1.0001) lies outside every tet of the mesh");
  P.col(1) = Eigen::Vector3d(40.0, -3.0, 2.5);  // beyond the mesh's box
  EXPECT_EQ(message_of([&] { (void)embed_in_tets(m, P); }), "point 1 (40, -3, 2.5) lies outside every tet of the mesh");
}

TEST(EmbedTets, ConcaveMeshLeavesTheNotchOut) {
  // Tets of an L: box_tets(4) without the tets whose centroid has x > 0 and y > 0.
  const VolumeMesh full = box_tets(4);
  VolumeMesh m = full;
  std::vector<int> keep;
  for (Eigen::Index c = 0; c < full.cell_count(); ++c) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a) centroid += 0.25 * full.vertices.col(full.cells(a, c));
    if (!(centroid.x() > 0 && centroid.y() > 0)) keep.push_back(static_cast<int>(c));
  }
  m.cells.resize(4, static_cast<Eigen::Index>(keep.size()));
  for (std::size_t c = 0; c < keep.size(); ++c) m.cells.col(static_cast<Eigen::Index>(c)) = full.cells.col(keep[c]);
  Eigen::Matrix3Xd P(3, 3);
  P << -0.5, 1e-7, 0.5,  //
      0.5, 0.3, 0.5,      //
      0.0, 0.1, 0.0;
  const Embedding e = embed_in_tets(m, P.leftCols(2));  // the second just across the notch's wall x = 0: clamped
  EXPECT_NEAR(e.apply(m.vertices)(0, 1), 0.0, 1e-15);
  EXPECT_EQ(message_of([&] { (void)embed_in_tets(m, P); }), "point 2 (0.5, 0.5, 0) lies outside every tet of the mesh");
  P.col(2) = Eigen::Vector3d(1e-4, 0.3, 0.1);  // across the wall by more than 1e-6 of the diagonal
  EXPECT_EQ(message_of([&] { (void)embed_in_tets(m, P); }), "point 2 (0.0001, 0.3, 0.1) lies outside every tet of the mesh");
}

TEST(EmbedTets, ManyPointsInALargeMesh) {
  // 10^4 points in the 384,000 tets of box_tets(40) (timing is not asserted; it takes a fraction of a second).
  const VolumeMesh m = box_tets(40, TetSplit::mirrored);
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix3Xd P(3, 10000);
  for (Eigen::Index p = 0; p < P.cols(); ++p) P.col(p) = Eigen::Vector3d(u(rng), u(rng), u(rng));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Embedding one = embed_in_tets(m, P);
  omp_set_num_threads(2);
  const Embedding two = embed_in_tets(m, P);
  omp_set_num_threads(threads);
  check_weights(two, 4);
  EXPECT_EQ(one.cell, two.cell);
  EXPECT_EQ(one.weight, two.weight);
  EXPECT_LT(relative_error(two.apply(m.vertices), P), 1e-12);
  EXPECT_LT(relative_error(two.apply(kAffine(m.vertices)), kAffine(P)), 1e-12);
}

TEST(EmbedTets, RejectsBadInput) {
  const VolumeMesh m = box_tets(2);
  const Eigen::Matrix3Xd p = Eigen::Matrix3Xd::Zero(3, 1);
  EXPECT_NE(message_of([&] { (void)embed_in_tets(box_hexes(2), p); }).find("tet4"), std::string::npos);
  VolumeMesh bad = m;
  bad.cells(2, 7) = 1000;
  EXPECT_NE(message_of([&] { (void)embed_in_tets(bad, p); }).find("tet 7"), std::string::npos);
  bad = m;
  bad.vertices(0, 3) = std::numeric_limits<double>::infinity();
  EXPECT_NE(message_of([&] { (void)embed_in_tets(bad, p); }).find("vertex 3"), std::string::npos);
  Eigen::Matrix3Xd q = p;
  q(1, 0) = std::nan("");
  EXPECT_NE(message_of([&] { (void)embed_in_tets(m, q); }).find("point 0"), std::string::npos);
  // apply with too few positions, or a flat vector whose size is not a multiple of 3.
  const Embedding e = embed_in_tets(m, p);
  EXPECT_THROW((void)e.apply(Eigen::Matrix3Xd(m.vertices.leftCols(3))), std::invalid_argument);
  const Eigen::VectorXd flat = Eigen::VectorXd::Zero(3 * m.vertex_count() + 1);
  EXPECT_THROW((void)e.apply(flat), std::invalid_argument);
}

}  // namespace
}  // namespace snh
