// Winding numbers, enclosed volumes and the hex lattice of a closed surface (embed/).
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "embed/surfaces.hpp"
#include "snh/embed/embedding.hpp"
#include "snh/embed/lattice.hpp"
#include "snh/math/union_find.hpp"
#include "snh/embed/winding_number.hpp"

namespace snh {
namespace {

using test::Surface;

Eigen::Vector3i cube_of(const Lattice& L, int c) {
  return {c % L.dims.x(), (c / L.dims.x()) % L.dims.y(), c / (L.dims.x() * L.dims.y())};
}

Eigen::Vector3d grid_point(const Lattice& L, const Eigen::Vector3d& cube_units) {
  return L.origin + L.spacing * cube_units;
}

double lattice_volume(const Lattice& L) { return static_cast<double>(L.mesh.cell_count()) * std::pow(L.spacing, 3); }

// ---------------------------------------------------------------------------------------------------------
// Winding numbers and volumes

TEST(WindingNumber, BoxIsOneInsideZeroOutsideHalfOnAFace) {
  const Surface box = test::box_solid(2, [](int, int, int) { return true; });  // [−1, 1]³, 48 triangles
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> in(-0.99, 0.99), out(1.01, 3.0), sign(-1.0, 1.0);
  for (int t = 0; t < 200; ++t) {
    const Eigen::Vector3d p(in(rng), in(rng), in(rng));
    EXPECT_NEAR(winding_number(box.V, box.F, p), 1.0, 1e-10) << p.transpose();
    Eigen::Vector3d q(in(rng), in(rng), in(rng));
    q[t % 3] = sign(rng) < 0 ? -out(rng) : out(rng);
    EXPECT_NEAR(winding_number(box.V, box.F, q), 0.0, 1e-10) << q.transpose();
  }
  // A point inside a face (on no triangle edge: the quads' diagonals run y = ±z in cell units).
  EXPECT_NEAR(winding_number(box.V, box.F, Eigen::Vector3d(1.0, 0.2, 0.7)), 0.5, 1e-10);
  EXPECT_NEAR(winding_number(box.V, box.F, Eigen::Vector3d(0.3, -1.0, -0.45)), 0.5, 1e-10);
}

TEST(WindingNumber, IcosphereInsideAndOutside) {
  const Surface s = test::icosphere(3, 2.0, Eigen::Vector3d(0.5, -1.0, 3.0));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int t = 0; t < 100; ++t) {
    const Eigen::Vector3d d = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    const double r = 0.5 * (1.0 + u(rng));  // 0 .. 1: inside the inscribed ball (radius > 1.98)
    EXPECT_NEAR(winding_number(s.V, s.F, Eigen::Vector3d(0.5, -1.0, 3.0) + 1.9 * r * d), 1.0, 1e-10);
    EXPECT_NEAR(winding_number(s.V, s.F, Eigen::Vector3d(0.5, -1.0, 3.0) + (2.1 + 5 * r) * d), 0.0, 1e-10);
  }
  // Reversed orientation: −1 inside.
  Surface r = s;
  r.F.row(1).swap(r.F.row(2));
  EXPECT_NEAR(winding_number(r.V, r.F, Eigen::Vector3d(0.5, -1.0, 3.0)), -1.0, 1e-10);
}

TEST(WindingNumber, RejectsBadInput) {
  const Surface box = test::axis_box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  EXPECT_THROW((void)winding_number(box.V, box.F, Eigen::Vector3d(0, std::nan(""), 0)), std::invalid_argument);
  Surface bad = box;
  bad.F(1, 3) = static_cast<int>(bad.V.cols());
  EXPECT_THROW((void)winding_number(bad.V, bad.F, Eigen::Vector3d::Zero()), std::invalid_argument);
  bad = box;
  bad.V(2, 4) = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)winding_number(bad.V, bad.F, Eigen::Vector3d::Zero()), std::invalid_argument);
  EXPECT_EQ(winding_number(box.V, Eigen::Matrix3Xi(3, 0), Eigen::Vector3d::Zero()), 0.0);
}

TEST(EnclosedVolume, AxisBoxIsExactAndReversedIsNegative) {
  const Surface box = test::axis_box(Eigen::Vector3d(1.0, -2.0, 10.0), Eigen::Vector3d(1.5, 1.0, 12.0));
  EXPECT_NEAR(enclosed_volume(box.V, box.F), 0.5 * 3.0 * 2.0, 1e-13);
  Surface r = box;
  r.F.row(1).swap(r.F.row(2));
  EXPECT_NEAR(enclosed_volume(r.V, r.F), -3.0, 1e-13);
  const Surface l = test::box_solid(2, [](int i, int j, int) { return i == 0 || j == 0; });  // L: 6 of 8 cells
  EXPECT_NEAR(enclosed_volume(l.V, l.F), 6.0, 1e-13);
}

TEST(EnclosedVolume, RefinedIcosphereApproachesTheBall) {
  const double ball = 4.0 / 3.0 * std::numbers::pi * 27.0;  // radius 3
  double previous = 0.0;
  for (int s = 1; s <= 5; ++s) {
    const Surface sphere = test::icosphere(s, 3.0, Eigen::Vector3d(100.0, 0.0, -50.0));
    const double v = enclosed_volume(sphere.V, sphere.F);
    EXPECT_LT(v, ball);  // an inscribed polyhedron
    EXPECT_GT(v, previous);
    previous = v;
  }
  EXPECT_NEAR(previous / ball, 1.0, 2e-3);  // 20480 triangles
}

// ---------------------------------------------------------------------------------------------------------
// The lattice

/// Whether a point is inside the surface (winding number > ½).
using InsideTest = std::function<bool(const Eigen::Vector3d&)>;
InsideTest by_winding_number(const Surface& s) {
  return [&s](const Eigen::Vector3d& p) { return winding_number(s.V, s.F, p) > 0.5; };
}

/// The properties every lattice of a closed surface has.
void check_lattice(const Lattice& L, const Surface& s, const InsideTest& inside) {
  ASSERT_EQ(L.mesh.type, CellType::hex8);
  ASSERT_EQ(static_cast<double>(L.cell_at.size()), static_cast<double>(L.dims.prod()));
  ASSERT_GT(L.mesh.cell_count(), 0);
  const double h = L.spacing;
  // Cells in grid order, each the cube it stands for, corners in VolumeMesh order with positive volume.
  int previous = -1;
  int count = 0;
  std::vector<int> uses(static_cast<std::size_t>(L.mesh.vertex_count()), 0);
  // A cube split into pieces has consecutive cells, one per piece.
  for (int c = 0; c < L.dims.prod(); ++c) {
    const auto [first, last] = L.cells_of_cube(c);
    for (int cell = first; cell < last; ++cell) {
      ASSERT_EQ(cell, previous + 1);
      ASSERT_EQ(L.cube_of_cell[static_cast<std::size_t>(cell)], c);
      previous = cell;
      ++count;
      const Eigen::Vector3i ijk = cube_of(L, c);
      for (int a = 0; a < 8; ++a) {
        const Eigen::Vector3d expected =
            grid_point(L, (ijk + Eigen::Vector3i(a & 1, (a >> 1) & 1, (a >> 2) & 1)).cast<double>());
        ASSERT_LE((L.mesh.vertices.col(L.mesh.cells(a, cell)) - expected).norm(), 1e-12 * (1.0 + expected.norm()));
        ++uses[static_cast<std::size_t>(L.mesh.cells(a, cell))];
      }
      Eigen::Matrix3d J;
      J.col(0) = L.mesh.vertices.col(L.mesh.cells(1, cell)) - L.mesh.vertices.col(L.mesh.cells(0, cell));
      J.col(1) = L.mesh.vertices.col(L.mesh.cells(2, cell)) - L.mesh.vertices.col(L.mesh.cells(0, cell));
      J.col(2) = L.mesh.vertices.col(L.mesh.cells(4, cell)) - L.mesh.vertices.col(L.mesh.cells(0, cell));
      ASSERT_NEAR(J.determinant(), h * h * h, 1e-9 * h * h * h);
    }
  }
  EXPECT_EQ(count, L.mesh.cell_count());
  for (int u : uses) ASSERT_GT(u, 0);  // only the vertices the cells use
  // Vertices numbered in grid order (z, then y, then x; the copies of a split node together).
  for (Eigen::Index v = 1; v < L.mesh.vertex_count(); ++v) {
    const Eigen::Vector3d a = L.grid_coordinates(L.mesh.vertices.col(v - 1)), b = L.grid_coordinates(L.mesh.vertices.col(v));
    const bool increasing = std::round(a.z()) < std::round(b.z()) ||
                            (std::round(a.z()) == std::round(b.z()) &&
                             (std::round(a.y()) < std::round(b.y()) ||
                              (std::round(a.y()) == std::round(b.y()) && std::round(a.x()) < std::round(b.x()))));
    ASSERT_TRUE(increasing || (a - b).norm() < 1e-9) << "vertex " << v;
  }
  // The surface's vertices (those the triangles use).
  std::vector<char> used(static_cast<std::size_t>(s.V.cols()), 0);
  for (Eigen::Index f = 0; f < s.F.cols(); ++f)
    for (int a = 0; a < 3; ++a) used[static_cast<std::size_t>(s.F(a, f))] = 1;
  Eigen::Matrix3Xd surface(3, std::count(used.begin(), used.end(), 1));
  for (Eigen::Index v = 0, n = 0; v < s.V.cols(); ++v)
    if (used[static_cast<std::size_t>(v)]) surface.col(n++) = s.V.col(v);
  // The grid holds the surface with a margin: no surface vertex within 1% of a cube of its outer faces.
  for (Eigen::Index v = 0; v < surface.cols(); ++v) {
    const Eigen::Vector3d q = L.grid_coordinates(surface.col(v));
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(q[a], 0.01);
      EXPECT_LT(q[a], L.dims[a] - 0.01);
    }
  }
  // Every surface vertex lies in a kept cube (the cube floor(q), or one whose face it is on).
  EXPECT_NO_THROW((void)embed_in_lattice(L, surface));
  for (Eigen::Index v = 0; v < surface.cols(); ++v) {
    const Eigen::Vector3d q = L.grid_coordinates(surface.col(v));
    const int i = static_cast<int>(std::floor(q.x())), j = static_cast<int>(std::floor(q.y())),
              k = static_cast<int>(std::floor(q.z()));
    EXPECT_GE(L.cell_at[static_cast<std::size_t>(L.cube_index(i, j, k))], 0) << "surface vertex " << v;
  }
  // Any cube holding a point of the solid is kept: sample its corners, centre and a few random points.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int c = 0; c < L.dims.prod(); ++c) {
    const Eigen::Vector3d ijk = cube_of(L, c).cast<double>();
    std::vector<Eigen::Vector3d> samples = {ijk + Eigen::Vector3d::Constant(0.5)};
    for (int a = 0; a < 8; ++a) samples.push_back(ijk + Eigen::Vector3d(a & 1, (a >> 1) & 1, (a >> 2) & 1));
    for (int r = 0; r < 3; ++r) samples.push_back(ijk + Eigen::Vector3d(u(rng), u(rng), u(rng)));
    bool any_inside = false;
    for (const auto& q : samples) any_inside = any_inside || inside(grid_point(L, q));
    if (any_inside) {
      EXPECT_GE(L.cell_at[static_cast<std::size_t>(c)], 0) << "cube " << ijk.transpose();
    }
  }
}

/// Every cell reaches every other through shared faces.
bool face_connected(const Lattice& L) {
  std::vector<char> seen(L.cell_at.size(), 0);
  int first = -1;
  for (int c = 0; c < L.dims.prod() && first < 0; ++c)
    if (L.cell_at[static_cast<std::size_t>(c)] >= 0) first = c;
  std::vector<int> stack = {first};
  seen[static_cast<std::size_t>(first)] = 1;
  int reached = 0;
  while (!stack.empty()) {
    const int c = stack.back();
    stack.pop_back();
    ++reached;
    const Eigen::Vector3i ijk = cube_of(L, c);
    for (int a = 0; a < 3; ++a)
      for (int d : {-1, 1}) {
        Eigen::Vector3i n = ijk;
        n[a] += d;
        if (n[a] < 0 || n[a] >= L.dims[a]) continue;
        const int m = L.cube_index(n.x(), n.y(), n.z());
        if (L.cell_at[static_cast<std::size_t>(m)] < 0 || seen[static_cast<std::size_t>(m)]) continue;
        seen[static_cast<std::size_t>(m)] = 1;
        stack.push_back(m);
      }
  }
  return reached == L.mesh.cell_count();
}

TEST(Lattice, SphereAtFourResolutions) {
  const double r = 1.3;
  const Eigen::Vector3d centre(0.21, -0.37, 0.05);
  for (int subdivisions : {2, 4}) {
    const Surface s = test::icosphere(subdivisions, r, centre);
    const double volume = enclosed_volume(s.V, s.F);
    // Inside the inscribed ball (the smallest distance from the centre to a triangle's plane) is inside, beyond
    // the circumscribed one outside; the winding number decides between.
    double inscribed = r;
    for (Eigen::Index f = 0; f < s.F.cols(); ++f) {
      const Eigen::Vector3d a = s.V.col(s.F(0, f)) - centre, b = s.V.col(s.F(1, f)) - centre, c = s.V.col(s.F(2, f)) - centre;
      inscribed = std::min(inscribed, std::abs(a.dot((b - a).cross(c - a).normalized())));
    }
    const InsideTest inside = [&](const Eigen::Vector3d& p) {
      const double d = (p - centre).norm();
      if (d < inscribed * (1 - 1e-12)) return true;
      if (d > r * (1 + 1e-12)) return false;
      return winding_number(s.V, s.F, p) > 0.5;
    };
    double previous_excess = std::numeric_limits<double>::infinity();
    for (int res : {4, 8, 16, 32}) {
      SCOPED_TRACE("subdivisions " + std::to_string(subdivisions) + ", resolution " + std::to_string(res));
      const Lattice L = lattice_for_surface(s.V, s.F, res);
      EXPECT_EQ(L.dims.maxCoeff(), res);  // the sphere's box is a cube: res cubes along every side
      EXPECT_EQ(L.dims.minCoeff(), res);
      check_lattice(L, s, inside);
      EXPECT_TRUE(face_connected(L));
      const double excess = lattice_volume(L) - volume;
      EXPECT_GE(excess, 0.0);
      EXPECT_LT(excess, 0.65 * previous_excess);  // about halves as the cubes halve
      previous_excess = excess;
      // A kept cube with its corners and centre outside must be one a triangle reaches: it meets the
      // circumscribed ball (the icosphere's vertices lie on it, so its triangles lie inside).
      for (int c = 0; c < L.dims.prod(); ++c) {
        if (L.cell_at[static_cast<std::size_t>(c)] < 0) continue;
        const Eigen::Vector3d lo = grid_point(L, cube_of(L, c).cast<double>());
        const Eigen::Vector3d nearest = centre.cwiseMax(lo).cwiseMin(lo + Eigen::Vector3d::Constant(L.spacing));
        EXPECT_LE((nearest - centre).norm(), r * (1 + 1e-12)) << "cube " << cube_of(L, c).transpose();
      }
      std::printf("sphere (%d subdivisions, %d triangles, volume %.6f) at resolution %d: %d cells, h %.6f, volume %.6f\n",
                  subdivisions, static_cast<int>(s.F.cols()), volume, res, static_cast<int>(L.mesh.cell_count()),
                  L.spacing, lattice_volume(L));
    }
  }
}

/// Whether the cube [lo, lo + h]³ and the tet (x0..x3) overlap, by separating axes (exact for two convex
/// polytopes: the cube's 3 normals, the tet's 4 face normals, the 18 products of a cube edge and a tet edge);
/// nullopt when some axis leaves them within `margin` of touching (too close to call).
std::optional<bool> cube_meets_tet(const Eigen::Vector3d& lo, double h, const std::array<Eigen::Vector3d, 4>& x,
                                   double margin) {
  std::vector<Eigen::Vector3d> axes = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  const int faces[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  for (const auto& f : faces) axes.push_back((x[f[1]] - x[f[0]]).cross(x[f[2]] - x[f[0]]));
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      for (int c = 0; c < 3; ++c) axes.push_back(Eigen::Vector3d::Unit(c).cross(x[b] - x[a]));
  bool close = false;
  for (Eigen::Vector3d axis : axes) {
    if (axis.norm() < 1e-12) continue;
    axis.normalize();
    double cube_lo = std::numeric_limits<double>::infinity(), cube_hi = -cube_lo, tet_lo = cube_lo, tet_hi = -cube_lo;
    for (int a = 0; a < 8; ++a) {
      const double p = axis.dot(lo + h * Eigen::Vector3d(a & 1, (a >> 1) & 1, (a >> 2) & 1));
      cube_lo = std::min(cube_lo, p);
      cube_hi = std::max(cube_hi, p);
    }
    for (const auto& v : x) {
      tet_lo = std::min(tet_lo, axis.dot(v));
      tet_hi = std::max(tet_hi, axis.dot(v));
    }
    const double gap = std::max(tet_lo - cube_hi, cube_lo - tet_hi);
    if (gap > margin) return false;
    if (gap > -margin) close = true;
  }
  if (close) return std::nullopt;
  return true;
}

TEST(Lattice, ConvexSolidKeepsExactlyTheCubesItMeets) {
  // For a convex solid the lattice is exactly the cubes that meet it (through its surface or wholly inside),
  // checked by an independent cube–tet separating-axis test.
  const std::array<Eigen::Vector3d, 4> x = {Eigen::Vector3d(0.013, -0.21, 0.05), Eigen::Vector3d(2.31, 0.17, -0.33),
                                            Eigen::Vector3d(0.71, 1.93, 0.29), Eigen::Vector3d(0.52, 0.61, 1.77)};
  Surface s;
  s.V.resize(3, 4);
  for (int a = 0; a < 4; ++a) s.V.col(a) = x[static_cast<std::size_t>(a)];
  s.F.resize(3, 4);
  s.F << 0, 0, 0, 1,  //
      2, 1, 3, 2,     //
      1, 3, 2, 3;
  ASSERT_GT(enclosed_volume(s.V, s.F), 0.0);
  for (int res : {3, 7, 16, 29}) {
    SCOPED_TRACE("resolution " + std::to_string(res));
    const Lattice L = lattice_for_surface(s.V, s.F, res);
    check_lattice(L, s, by_winding_number(s));
    int met = 0, undecided = 0;
    for (int c = 0; c < L.dims.prod(); ++c) {
      const std::optional<bool> meets = cube_meets_tet(grid_point(L, cube_of(L, c).cast<double>()), L.spacing, x,
                                                       1e-7 * L.spacing);
      if (!meets) {
        ++undecided;
        continue;
      }
      met += *meets ? 1 : 0;
      EXPECT_EQ(L.cell_at[static_cast<std::size_t>(c)] >= 0, *meets) << "cube " << cube_of(L, c).transpose();
    }
    EXPECT_EQ(undecided, 0);
    EXPECT_GT(met, 0);
  }
}

TEST(Lattice, AxisBoxFillsItsGrid) {
  // The padding keeps the box's faces off the grid planes: the lattice of [0,1]³ at resolution n is n³ cubes.
  const Surface box = test::axis_box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  const Lattice one = lattice_for_surface(box.V, box.F, 1);
  EXPECT_EQ(one.mesh.cell_count(), 1);
  EXPECT_EQ(one.mesh.vertex_count(), 8);
  check_lattice(one, box, by_winding_number(box));
  const Lattice L = lattice_for_surface(box.V, box.F, 5);
  EXPECT_EQ(L.mesh.cell_count(), 125);
  check_lattice(L, box, by_winding_number(box));
}

TEST(Lattice, ThinSlabAndRodAreCovered) {
  // A slab 0.01 thick, tilted, and a square rod as thin along a skew diagonal: a tenth of a cube or less.
  const int res = 12;
  const double thickness = 0.01;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1.0, 0.3, -0.2).normalized()).toRotationMatrix();
  const Eigen::Matrix3d slab_scale = Eigen::Vector3d(1.0, 0.8, 0.5 * thickness).asDiagonal();
  const Eigen::Matrix3d rod_scale = Eigen::Vector3d(1.0, 0.5 * thickness, 0.5 * thickness).asDiagonal();
  const Eigen::Matrix3d toward_diagonal =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), Eigen::Vector3d(1.0, 0.9, 1.1)).toRotationMatrix();
  const Eigen::Vector3d offset(0.0123, -0.0456, 0.0789);
  const std::array<Surface, 2> shapes = {
      test::box_solid(3, [](int, int, int) { return true; }, R * slab_scale, offset),
      test::box_solid(1, [](int, int, int) { return true; }, toward_diagonal * rod_scale, offset)};
  for (int shape = 0; shape < 2; ++shape) {
    SCOPED_TRACE(shape == 0 ? "slab" : "rod");
    const Surface& s = shapes[static_cast<std::size_t>(shape)];
    ASSERT_GT(enclosed_volume(s.V, s.F), 0.0);
    const Lattice L = lattice_for_surface(s.V, s.F, res);
    EXPECT_LE(thickness, 0.11 * L.spacing);
    check_lattice(L, s, by_winding_number(s));
    EXPECT_TRUE(face_connected(L));
    // Points of the mid-surface or axis lie in kept cubes.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix3Xd mid(3, 500);
    const Eigen::Matrix3d A = shape == 0 ? Eigen::Matrix3d(R * slab_scale) : Eigen::Matrix3d(toward_diagonal * rod_scale);
    for (Eigen::Index p = 0; p < mid.cols(); ++p)
      mid.col(p) = A * Eigen::Vector3d(u(rng), shape == 0 ? u(rng) : 0.0, 0.0) + offset;
    EXPECT_NO_THROW((void)embed_in_lattice(L, mid));
  }
}

TEST(Lattice, NonConvexSolidsLeaveTheNotchOut) {
  // An L (the quarter x > 0, y > 0 of [−1, 1]³ removed) and a U (the slot −0.5 < x < 0.5, y > 0 removed),
  // shifted and stretched a little so the grid does not line up with their faces.
  const Eigen::Matrix3d A = Eigen::Vector3d(1.07, 0.93, 1.0).asDiagonal();
  const Eigen::Vector3d b(0.031, -0.017, 0.2);
  const Surface L_shape = test::box_solid(4, [](int i, int j, int) { return i < 2 || j < 2; }, A, b);
  const Surface U_shape = test::box_solid(4, [](int i, int j, int) { return i == 0 || i == 3 || j < 2; }, A, b);
  const std::array<std::pair<const Surface*, std::array<double, 2>>, 2> cases = {
      {{&L_shape, {0.0, 1.0}}, {&U_shape, {-0.5, 0.5}}}};  // the notch's x range before the map
  for (int res : {6, 9, 16}) {
    for (const auto& [s, notch] : cases) {
      SCOPED_TRACE("resolution " + std::to_string(res));
      const Lattice L = lattice_for_surface(s->V, s->F, res);
      check_lattice(L, *s, by_winding_number(*s));
      EXPECT_TRUE(face_connected(L));
      const double x0 = A(0, 0) * notch[0] + b.x(), x1 = A(0, 0) * notch[1] + b.x(), y0 = b.y();
      int in_notch = 0;
      for (int c = 0; c < L.dims.prod(); ++c) {
        const Eigen::Vector3d lo = grid_point(L, cube_of(L, c).cast<double>());
        const Eigen::Vector3d hi = lo + Eigen::Vector3d::Constant(L.spacing);
        const double margin = 1e-6 * L.spacing;
        if (lo.x() > x0 + margin && hi.x() < x1 - margin && lo.y() > y0 + margin) {  // no triangle reaches it
          ++in_notch;
          EXPECT_LT(L.cell_at[static_cast<std::size_t>(c)], 0) << "cube " << cube_of(L, c).transpose();
        }
      }
      EXPECT_GT(in_notch, 0);
      EXPECT_GE(lattice_volume(L), enclosed_volume(s->V, s->F));
    }
  }
}

TEST(Lattice, DeterministicForAnyThreadCount) {
  const Surface s = test::icosphere(4, 1.0, Eigen::Vector3d(0.1, 0.2, 0.3));
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Lattice a = lattice_for_surface(s.V, s.F, 24);
  omp_set_num_threads(2);
  const Lattice b = lattice_for_surface(s.V, s.F, 24);
  const Lattice c = lattice_for_surface(s.V, s.F, 24);
  omp_set_num_threads(threads);
  for (const Lattice* other : {&b, &c}) {
    EXPECT_EQ(a.dims, other->dims);
    EXPECT_EQ(a.origin, other->origin);
    EXPECT_EQ(a.spacing, other->spacing);
    EXPECT_EQ(a.cell_at, other->cell_at);
    EXPECT_EQ(a.mesh.cells, other->mesh.cells);
    EXPECT_EQ(a.mesh.vertices, other->mesh.vertices);
  }
}

TEST(Lattice, RejectsBadInput) {
  const Surface s = test::icosphere(1);
  const auto message = [&](const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int res) -> std::string {
    try {
      (void)lattice_for_surface(V, F, res);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(no exception)";
  };
  EXPECT_NE(message(s.V, s.F, 0).find("resolution must be >= 1, got 0"), std::string::npos);
  EXPECT_NE(message(s.V, s.F, -4).find("-4"), std::string::npos);
  EXPECT_NE(message(s.V, s.F, 1000000).find("resolution 1000000"), std::string::npos);
  Eigen::Matrix3Xd nan = s.V;
  nan(1, 7) = std::nan("");
  EXPECT_NE(message(nan, s.F, 8).find("vertex 7"), std::string::npos);
  EXPECT_NE(message(s.V, Eigen::Matrix3Xi(3, 0), 8).find("no triangles"), std::string::npos);
  Eigen::Matrix3Xi out = s.F;
  out(2, 5) = static_cast<int>(s.V.cols());
  EXPECT_NE(message(s.V, out, 8).find("triangle 5"), std::string::npos);
  out(2, 5) = -1;
  EXPECT_NE(message(s.V, out, 8).find("triangle 5"), std::string::npos);
  const Eigen::Matrix3Xd point = Eigen::Matrix3Xd::Ones(3, s.V.cols());
  EXPECT_NE(message(point, s.F, 8).find("no extent"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------
// Pieces: cubes the surface splits (the virtual node algorithm)

namespace pieces {

Surface join(const Surface& a, const Surface& b) {
  Surface s;
  s.V.resize(3, a.V.cols() + b.V.cols());
  s.V << a.V, b.V;
  s.F.resize(3, a.F.cols() + b.F.cols());
  s.F << a.F, (b.F.array() + static_cast<int>(a.V.cols())).matrix();
  return s;
}

/// The cells' components when cells sharing a vertex are connected: the component of each cell.
std::vector<int> components(const Lattice& L, int& count) {
  const auto n = static_cast<int>(L.mesh.cell_count());
  UnionFind groups(static_cast<std::size_t>(n));
  const auto root = [&](int i) { return groups.root(i); };
  std::vector<int> cell_of_vertex(static_cast<std::size_t>(L.mesh.vertex_count()), -1);
  for (int c = 0; c < n; ++c)
    for (int k = 0; k < 8; ++k) {
      int& first = cell_of_vertex[static_cast<std::size_t>(L.mesh.cells(k, c))];
      if (first < 0) first = c;
      else groups.join(c, first);
    }
  std::vector<int> id(static_cast<std::size_t>(n), -1), out(static_cast<std::size_t>(n));
  count = 0;
  for (int c = 0; c < n; ++c) {
    int& r = id[static_cast<std::size_t>(root(c))];
    if (r < 0) r = count++;
    out[static_cast<std::size_t>(c)] = r;
  }
  return out;
}

/// Two boxes 1.0 × 1.0 × 2.0 side by side along x, `gap` apart, tilted a little so no face lies on the grid.
Surface two_boxes(double gap) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.13, Eigen::Vector3d(0.2, 1.0, 0.4).normalized()).toRotationMatrix();
  Surface a = test::axis_box(Eigen::Vector3d(-1.0 - 0.5 * gap, -0.5, -1.0), Eigen::Vector3d(-0.5 * gap, 0.5, 1.0));
  Surface b = test::axis_box(Eigen::Vector3d(0.5 * gap, -0.5, -1.0), Eigen::Vector3d(1.0 + 0.5 * gap, 0.5, 1.0));
  a.V = R * a.V;
  b.V = R * b.V;
  return join(a, b);
}

}  // namespace pieces

TEST(LatticePieces, NothingToSeparateGivesTheLatticeWithoutPieces) {
  // Solids whose every cube holds one piece: the lattice is the same with pieces sought as without.
  // Two meshes that overlap (as a head pushed into a neck) are one solid: the surfaces inside it separate nothing.
  const std::array<Surface, 3> shapes = {test::icosphere(3, 1.3, Eigen::Vector3d(0.1, 0.2, -0.3)),
                                         test::box_solid(4, [](int i, int j, int) { return i != 1 || j != 2; }),  // a hole through
                                         pieces::two_boxes(-0.37)};
  for (std::size_t s = 0; s < shapes.size(); ++s)
    for (int res : {5, 11, 17}) {
      SCOPED_TRACE("shape " + std::to_string(s) + ", resolution " + std::to_string(res));
      const Lattice with = lattice_for_surface(shapes[s].V, shapes[s].F, res);
      const Lattice without = lattice_for_surface(shapes[s].V, shapes[s].F, res, 0);
      EXPECT_EQ(with.split_cubes, 0);
      EXPECT_TRUE(with.mesh.cells == without.mesh.cells);
      EXPECT_TRUE(with.mesh.vertices == without.mesh.vertices);
      EXPECT_TRUE(with.cell_at == without.cell_at);
      EXPECT_TRUE(std::all_of(with.copies.begin(), with.copies.end(), [](int c) { return c == 1; }));
    }
}

TEST(LatticePieces, PartsCloserThanACubeAreNotJoined) {
  // Two boxes a third of a cube apart: without pieces the cubes over the gap glue them into one solid; with
  // them the lattice falls apart into two, each cell of a split cube standing for one box.
  const Surface s = pieces::two_boxes(0.1);
  const Lattice glued = lattice_for_surface(s.V, s.F, 8, 0);
  ASSERT_GT(glued.spacing, 0.25);  // the gap, 0.1, under a third of a cube (and over a sample's spacing)
  int count = 0;
  (void)pieces::components(glued, count);
  EXPECT_EQ(count, 1);
  const Lattice L = lattice_for_surface(s.V, s.F, 8);
  EXPECT_GT(L.split_cubes, 0);
  const std::vector<int> part = pieces::components(L, count);
  EXPECT_EQ(count, 2);
  EXPECT_EQ(L.mesh.cell_count(), glued.mesh.cell_count() + L.split_cubes);  // two pieces per split cube
  check_lattice(L, s, by_winding_number(s));
  // Each box's surface points lie in cells of one component, a different one for each box.
  Eigen::Matrix3Xd points(3, s.V.cols());
  points = s.V;
  std::vector<int> vertex(static_cast<std::size_t>(s.V.cols()));
  for (std::size_t v = 0; v < vertex.size(); ++v) vertex[v] = static_cast<int>(v);
  const Embedding e = embed_surface_in_lattice(L, s.V, s.F, points, vertex);
  const Eigen::Index half = s.V.cols() / 2;
  for (Eigen::Index v = 0; v < s.V.cols(); ++v)
    EXPECT_EQ(part[static_cast<std::size_t>(e.cell[static_cast<std::size_t>(v)])],
              part[static_cast<std::size_t>(e.cell[v < half ? 0 : static_cast<std::size_t>(half)])])
        << "vertex " << v;
  EXPECT_NE(part[static_cast<std::size_t>(e.cell[0])], part[static_cast<std::size_t>(e.cell[static_cast<std::size_t>(half)])]);
  // Points strewn over each box (inside) go with it: the piece of their nearest sample.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.13, Eigen::Vector3d(0.2, 1.0, 0.4).normalized()).toRotationMatrix();
  Eigen::Matrix3Xd inner(3, 200);
  for (Eigen::Index p = 0; p < inner.cols(); ++p)
    inner.col(p) = R * Eigen::Vector3d((p % 2 ? 1.0 : -1.0) * (0.5 + 0.05 + u(rng) + 0.0), u(rng), 2.0 * u(rng));
  const Embedding ei = embed_in_lattice(L, inner);
  for (Eigen::Index p = 0; p < inner.cols(); ++p)
    EXPECT_EQ(part[static_cast<std::size_t>(ei.cell[static_cast<std::size_t>(p)])],
              part[static_cast<std::size_t>(e.cell[p % 2 ? static_cast<std::size_t>(half) : 0])])
        << "point " << p;
  // Every vertex of a split cube's cells at a node holds its copies: the node is doubled there.
  EXPECT_TRUE(std::any_of(L.copies.begin(), L.copies.end(), [](int c) { return c == 2; }));
}

TEST(LatticePieces, PartsWhoseCubesMeetOnlyAtAnEdgeOrCornerAreNotJoined) {
  // Two boxes 0.9 apart, cubes 0.6 wide: no cube holds both, but some of their cubes meet along an edge or at
  // a corner across the gap, where one cell per cube joined them.
  const Surface s = pieces::two_boxes(0.9);
  for (int res : {5, 11, 17}) {
    int count = 0;
    (void)pieces::components(lattice_for_surface(s.V, s.F, res), count);
    EXPECT_EQ(count, 2) << "resolution " << res;
  }
  int glued = 0;
  (void)pieces::components(lattice_for_surface(s.V, s.F, 5, 0), glued);
  EXPECT_EQ(glued, 1);
}

TEST(LatticePieces, ThinAndDiagonalMaterialIsOnePiece) {
  // Material thinner than a sample's spacing, or running diagonally across a cube, leaves its samples
  // unconnected along the axes: it is still one piece (the slab and rod of ThinSlabAndRodAreCovered), and
  // a convex solid never splits.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1.0, 0.3, -0.2).normalized()).toRotationMatrix();
  const Surface slab = test::box_solid(3, [](int, int, int) { return true; }, R * Eigen::Vector3d(1.0, 0.8, 0.02).asDiagonal(),
                                       Eigen::Vector3d(0.0123, -0.0456, 0.0789));
  for (int res : {4, 9, 12}) {
    const Lattice L = lattice_for_surface(slab.V, slab.F, res);
    EXPECT_EQ(L.split_cubes, 0) << "resolution " << res;
    int count = 0;
    (void)pieces::components(L, count);
    EXPECT_EQ(count, 1) << "resolution " << res;
  }
}

TEST(LatticePieces, SegmentMeetsTriangle) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(segment_meets_triangle({0.2, 0.2, -1}, {0.2, 0.2, 1}, a, b, c));
  EXPECT_TRUE(segment_meets_triangle({0.2, 0.2, 1}, {0.2, 0.2, -1}, a, c, b));  // either orientation
  EXPECT_FALSE(segment_meets_triangle({0.7, 0.7, -1}, {0.7, 0.7, 1}, a, b, c));  // beyond the hypotenuse
  EXPECT_FALSE(segment_meets_triangle({0.2, 0.2, 0.1}, {0.2, 0.2, 1}, a, b, c));  // short of the plane
  EXPECT_TRUE(segment_meets_triangle({0.5, 0.5, -1}, {0.5, 0.5, 1}, a, b, c));   // through an edge: touching
  EXPECT_TRUE(segment_meets_triangle({0.2, 0.2, 0}, {0.2, 0.2, 1}, a, b, c));    // an end on the triangle
  EXPECT_FALSE(segment_meets_triangle({-1, 0.2, 0}, {2, 0.2, 0}, a, b, c));      // in its plane
}

TEST(LatticePieces, SoupsOfRandomTrianglesBuildAndEmbed) {
  // Overlapping, open, inside-out, degenerate: whatever the triangles, the lattice is built, its cells are whole
  // cubes, every triangle's vertices embed in it (in a cell of their cube), and samples out of range are refused.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    SCOPED_TRACE("soup " + std::to_string(trial));
    Surface s;
    const int triangles = 10 + trial * 4;
    s.V.resize(3, 3 * triangles);
    s.F.resize(3, triangles);
    for (int t = 0; t < triangles; ++t) {
      const Eigen::Vector3d centre(u(rng), u(rng), u(rng));
      for (int k = 0; k < 3; ++k) {
        // Every fifth triangle degenerate (two corners equal).
        s.V.col(3 * t + k) = (t % 5 == 0 && k == 2) ? Eigen::Vector3d(s.V.col(3 * t + 1)) : Eigen::Vector3d(centre + 0.4 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
        s.F(k, t) = 3 * t + k;
      }
    }
    const Lattice L = lattice_for_surface(s.V, s.F, 6 + trial % 5);
    for (Eigen::Index c = 0; c < L.mesh.cell_count(); ++c) {
      Eigen::Matrix3d J;
      for (int a = 0; a < 3; ++a) J.col(a) = L.mesh.vertices.col(L.mesh.cells(1 << a, c)) - L.mesh.vertices.col(L.mesh.cells(0, c));
      ASSERT_NEAR(J.determinant(), std::pow(L.spacing, 3), 1e-9 * std::pow(L.spacing, 3)) << "cell " << c;
    }
    std::vector<int> vertex(static_cast<std::size_t>(s.V.cols()));
    for (std::size_t v = 0; v < vertex.size(); ++v) vertex[v] = static_cast<int>(v);
    const Embedding e = embed_surface_in_lattice(L, s.V, s.F, s.V, vertex);
    EXPECT_LT((e.apply(L.mesh.vertices) - s.V).cwiseAbs().maxCoeff(), 1e-9);
  }
  const Surface box = test::axis_box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones());
  EXPECT_THROW((void)lattice_for_surface(box.V, box.F, 4, -1), std::invalid_argument);
  EXPECT_THROW((void)lattice_for_surface(box.V, box.F, 4, 17), std::invalid_argument);
}

}  // namespace
}  // namespace snh
