// Box generators (docs/paper-programs.md) and boundary-surface extraction.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "snh/fem/quality.hpp"
#include "snh/fem/rest_state.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"

namespace snh {
namespace {

TEST(Box, LatticeOrderAndPositions) {
  const Eigen::Matrix3Xd V = box_lattice(4);
  ASSERT_EQ(V.cols(), 125);
  EXPECT_EQ(lattice_index(4, 1, 2, 3), 1 + 2 * 5 + 3 * 25);
  EXPECT_TRUE(V.col(0).isApprox(Eigen::Vector3d(-1, -1, -1)));
  EXPECT_TRUE(V.col(lattice_index(4, 1, 2, 3)).isApprox(Eigen::Vector3d(-0.5, 0.0, 0.5)));
  EXPECT_TRUE(V.col(124).isApprox(Eigen::Vector3d(1, 1, 1)));
}

TEST(Box, TetsAreTheSixTemplatesWithPositiveVolume) {
  const VolumeMesh m = box_tets(10);
  EXPECT_EQ(m.cell_count(), 6000);  // docs/paper-programs.md: res 10 -> 6000 tets
  EXPECT_EQ(m.vertex_count(), 1331);
  // First cell (0,0,0): corners c0 = 0, c7 = lattice (1,1,1); template {7,4,0,5} up to a swap of the last two.
  const int c7 = lattice_index(10, 1, 1, 1), c4 = lattice_index(10, 0, 0, 1), c5 = lattice_index(10, 1, 0, 1);
  EXPECT_EQ(m.cells(0, 0), c7);
  EXPECT_EQ(m.cells(1, 0), c4);
  EXPECT_TRUE((m.cells(2, 0) == 0 && m.cells(3, 0) == c5) || (m.cells(2, 0) == c5 && m.cells(3, 0) == 0));
  const Eigen::VectorXd vol = rest_volumes(compute_rest_state(m));
  EXPECT_GT(vol.minCoeff(), 0.0);
  EXPECT_NEAR(vol.sum(), 8.0, 1e-12);
  EXPECT_NEAR(vol.minCoeff(), 0.2 * 0.2 * 0.2 / 6.0, 1e-15);
}

TEST(Box, HexesUseTheCornerOrder) {
  const VolumeMesh m = box_hexes(3);
  EXPECT_EQ(m.cell_count(), 27);
  const int i = 1, j = 2, k = 0, res = 3;
  const int c = i + j * res + k * res * res;
  EXPECT_EQ(m.cells(0, c), lattice_index(res, i, j, k));
  EXPECT_EQ(m.cells(1, c), lattice_index(res, i + 1, j, k));
  EXPECT_EQ(m.cells(2, c), lattice_index(res, i, j + 1, k));
  EXPECT_EQ(m.cells(3, c), lattice_index(res, i + 1, j + 1, k));
  EXPECT_EQ(m.cells(7, c), lattice_index(res, i + 1, j + 1, k + 1));
  const Eigen::VectorXd vol = rest_volumes(compute_rest_state(m));
  EXPECT_NEAR(vol.sum(), 8.0, 1e-12);
}

TEST(Quality, BoxSummary) {
  const VolumeMesh t = box_tets(5);
  const MeshQuality qt = mesh_quality(t, compute_rest_state(t));
  EXPECT_EQ(qt.cells, 750);
  EXPECT_NEAR(qt.min_volume, 0.4 * 0.4 * 0.4 / 6, 1e-15);
  EXPECT_NEAR(qt.max_volume, 0.4 * 0.4 * 0.4 / 6, 1e-15);
  EXPECT_NEAR(qt.worst_edge_ratio, std::sqrt(3.0), 1e-12);  // the c0-c7 diagonal against a cell edge
  VolumeMesh h = box_hexes(2);
  h.vertices(0, lattice_index(2, 2, 2, 2)) = 1.5;  // stretch one corner hex
  const MeshQuality qh = mesh_quality(h, compute_rest_state(h));
  EXPECT_EQ(qh.worst_cell, 7);
  EXPECT_NEAR(qh.worst_edge_ratio, 1.5, 1e-12);  // the edge from (1,2,2) now 1.5 long, the shortest 1
  EXPECT_NEAR(qh.min_volume, 1.0, 1e-12);
  EXPECT_GT(qh.max_volume, 1.0);
  EXPECT_NE(describe(qt, CellType::tet4).find("750 tets"), std::string::npos);
}

TEST(Box, RejectsBadResolution) {
  EXPECT_THROW((void)box_tets(0), std::invalid_argument);
  EXPECT_THROW((void)box_hexes(-3), std::invalid_argument);
}

/// Closed, consistently outward surface enclosing volume 8, with two triangles per lattice quad.
void check_surface(const VolumeMesh& m, int res) {
  const Eigen::Matrix3Xi T = boundary_triangles(m);
  ASSERT_EQ(T.cols(), 6 * 2 * res * res);
  std::map<std::pair<int, int>, int> directed;
  double volume = 0.0;
  for (Eigen::Index f = 0; f < T.cols(); ++f) {
    const Eigen::Vector3d a = m.vertices.col(T(0, f)), b = m.vertices.col(T(1, f)), c = m.vertices.col(T(2, f));
    volume += a.dot(b.cross(c)) / 6.0;
    const Eigen::Vector3d n = (b - a).cross(c - a);
    EXPECT_GT(n.dot((a + b + c) / 3.0), 0.0) << "inward triangle " << f;  // the box is centred at 0
    for (int e = 0; e < 3; ++e) ++directed[{T(e, f), T((e + 1) % 3, f)}];
  }
  EXPECT_NEAR(volume, 8.0, 1e-12);
  for (const auto& [edge, count] : directed) {
    EXPECT_EQ(count, 1);
    EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << "open edge";
  }
}

TEST(Surface, TetBoxIsClosedAndOutward) { check_surface(box_tets(3), 3); }
// A non-conforming split would leave interior faces unmatched, which boundary_triangles would report.
TEST(Surface, MirroredTetBoxIsClosedAndOutward) {
  check_surface(box_tets(4, TetSplit::mirrored), 4);
  check_surface(box_tets(3, TetSplit::mirrored), 3);
}

/// The tets of m as sorted vertex sets, after mapping every lattice vertex through `map`.
std::set<std::array<int, 4>> tet_set(const VolumeMesh& m, const std::function<int(int)>& map) {
  std::set<std::array<int, 4>> out;
  for (Eigen::Index c = 0; c < m.cell_count(); ++c) {
    std::array<int, 4> t{map(m.cells(0, c)), map(m.cells(1, c)), map(m.cells(2, c)), map(m.cells(3, c))};
    std::sort(t.begin(), t.end());
    out.insert(t);
  }
  return out;
}

TEST(Box, MirroredTetSplitIsMirrorSymmetricInEachAxis) {
  const int res = 4, n = res + 1;
  for (TetSplit split : {TetSplit::paper, TetSplit::mirrored}) {
    const VolumeMesh m = box_tets(res, split);
    EXPECT_GT(rest_volumes(compute_rest_state(m)).minCoeff(), 0.0);
    const auto original = tet_set(m, [](int v) { return v; });
    for (int axis = 0; axis < 3; ++axis) {
      const auto mirrored = tet_set(m, [&](int v) {
        int ijk[3] = {v % n, (v / n) % n, v / (n * n)};
        ijk[axis] = res - ijk[axis];
        return lattice_index(res, ijk[0], ijk[1], ijk[2]);
      });
      if (split == TetSplit::mirrored) {
        EXPECT_EQ(mirrored, original) << "axis " << axis;
      }
      else EXPECT_NE(mirrored, original) << "the paper's split is not mirror symmetric (axis " << axis << ")";
    }
  }
}
TEST(Surface, HexBoxIsClosedAndOutward) { check_surface(box_hexes(3), 3); }

}  // namespace
}  // namespace snh
