#include "snh/embed/lattice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "snh/embed/winding_number.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/math/parallel.hpp"

namespace snh {
namespace {

constexpr double kPad = 0.05;                          ///< margin around the bounding box, in cubes, each side
constexpr std::int64_t kMaxCubes = std::int64_t{1} << 28;  ///< so (dims + 1)³ grid nodes still fit an int

/// Separating-axis test of a triangle against the cube [−e, e]³ (Akenine-Möller 2001's 13 axes: the
/// cube's normals, the triangle's normal, and the 9 products of an edge with a cube axis). v: the corners
/// relative to the cube's centre. A degenerate triangle (a segment or a point) is tested exactly as well:
/// its zero normal separates nothing and the other axes are those of a segment.
bool triangle_overlaps_cube(const std::array<Eigen::Vector3d, 3>& v, double e) {
  for (int a = 0; a < 3; ++a) {
    const double lo = std::min({v[0][a], v[1][a], v[2][a]}), hi = std::max({v[0][a], v[1][a], v[2][a]});
    if (lo > e || hi < -e) return false;
  }
  const auto separates = [&](const Eigen::Vector3d& axis) {
    const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
    const double r = e * axis.cwiseAbs().sum();
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
  };
  const std::array<Eigen::Vector3d, 3> edge = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  for (const Eigen::Vector3d& f : edge)
    for (int a = 0; a < 3; ++a)
      if (separates(Eigen::Vector3d::Unit(a).cross(f))) return false;
  return !separates(edge[0].cross(v[2] - v[0]));
}

/// The grid: `resolution` cubes along the longest side of the bounding box of the vertices the triangles use,
/// with kPad of a cube to spare at either end; the other sides get as many cubes as cover them with at least
/// that margin. The grid is centred on the box. Its cells are not chosen yet.
Lattice empty_grid(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution) {
  Eigen::Vector3d lo = V.col(F(0, 0)), hi = lo;
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int a = 0; a < 3; ++a) {
      lo = lo.cwiseMin(V.col(F(a, f)));
      hi = hi.cwiseMax(V.col(F(a, f)));
    }
  const Eigen::Vector3d extent = hi - lo;
  const double longest = extent.maxCoeff();
  if (!(longest > 0.0) || !std::isfinite(longest))
    throw std::invalid_argument(
        fmt::format("lattice of a surface with no extent (every vertex at ({}, {}, {}))", lo.x(), lo.y(), lo.z()));
  Lattice L;
  L.spacing = longest / (resolution - 2.0 * kPad);
  double cubes = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double n = std::max(1.0, std::ceil(extent[a] / L.spacing + 2.0 * kPad - 1e-9));
    cubes *= n;
    if (!(cubes <= static_cast<double>(kMaxCubes)))
      throw std::invalid_argument(fmt::format(
          "lattice resolution {} needs more than 2^28 cubes for a surface of extent ({}, {}, {})", resolution,
          extent.x(), extent.y(), extent.z()));
    L.dims[a] = static_cast<int>(n);
    L.origin[a] = lo[a] - 0.5 * (n * L.spacing - extent[a]);
  }
  return L;
}

/// The cubes a triangle overlaps (1), in cube units (L.grid_coordinates, as embed_in_lattice), each cube grown
/// by δ: 1e-9 of its edge, more for grids so long that rounding of the coordinates could exceed that.
std::vector<unsigned char> touched_cubes(const Lattice& L, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F) {
  const Eigen::Vector3i& dims = L.dims;
  const auto n_cubes = static_cast<std::size_t>(std::int64_t{dims.x()} * dims.y() * dims.z());
  const double delta = 1e-9 + 16.0 * std::numeric_limits<double>::epsilon() * dims.maxCoeff();
  Eigen::Matrix3Xd Q(3, V.cols());
  for (Eigen::Index v = 0; v < V.cols(); ++v) Q.col(v) = L.grid_coordinates(V.col(v));
  std::vector<unsigned char> touched(n_cubes, 0);
  const auto cube_range = [&](double x, int a) {
    return std::clamp(static_cast<int>(std::floor(std::clamp(x, -1.0, dims[a] + 1.0))), 0, dims[a] - 1);
  };
  ParallelErrors overlap_errors;
#pragma omp parallel for schedule(dynamic, 64) if (F.cols() >= 256)
  for (Eigen::Index f = 0; f < F.cols(); ++f) {
    overlap_errors.run(f, [&] {
      const std::array<Eigen::Vector3d, 3> q = {Q.col(F(0, f)), Q.col(F(1, f)), Q.col(F(2, f))};
      const Eigen::Vector3d qlo = q[0].cwiseMin(q[1]).cwiseMin(q[2]), qhi = q[0].cwiseMax(q[1]).cwiseMax(q[2]);
      std::array<int, 3> first{}, last{};
      for (int a = 0; a < 3; ++a) {
        first[a] = cube_range(qlo[a] - 2.0 * delta, a);
        last[a] = cube_range(qhi[a] + 2.0 * delta, a);
      }
      for (int k = first[2]; k <= last[2]; ++k)
        for (int j = first[1]; j <= last[1]; ++j)
          for (int i = first[0]; i <= last[0]; ++i) {
            const std::size_t c = static_cast<std::size_t>(L.cube_index(i, j, k));
            unsigned char seen;
#pragma omp atomic read
            seen = touched[c];
            if (seen) continue;
            const Eigen::Vector3d centre(i + 0.5, j + 0.5, k + 0.5);
            if (triangle_overlaps_cube({q[0] - centre, q[1] - centre, q[2] - centre}, 0.5 + delta)) {
#pragma omp atomic write
              touched[c] = 1;
            }
          }
    });
  }
  overlap_errors.rethrow();
  return touched;
}

/// Whether each untouched cube is inside, |winding number| > ½ (either orientation): untouched cubes, grouped
/// by face neighbours into regions the surface does not cross; on a closed surface each region is inside or
/// outside as a whole (the winding number is constant off the surface), asked at its first cube; on an open
/// one (`open`: holes let a region reach from inside to outside, where the generalized winding number varies
/// smoothly) every cube is asked. Touched cubes come back 0.
std::vector<unsigned char> inside_cubes(const Lattice& L, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F,
                                        const std::vector<unsigned char>& touched, bool open) {
  const Eigen::Vector3i& dims = L.dims;
  const std::size_t n_cubes = touched.size();
  std::vector<int> region(n_cubes, -1);
  std::vector<int> seed;  // each region's first cube in grid order
  std::vector<int> stack;
  for (std::size_t c0 = 0; c0 < n_cubes; ++c0) {
    if (touched[c0] || region[c0] >= 0) continue;
    const int r = static_cast<int>(seed.size());
    seed.push_back(static_cast<int>(c0));
    region[c0] = r;
    if (open) continue;  // a region per cube
    stack.assign(1, static_cast<int>(c0));
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const int i = c % dims.x(), j = (c / dims.x()) % dims.y(), k = c / (dims.x() * dims.y());
      const std::array<std::array<int, 3>, 6> next = {
          {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}}};
      for (const auto& n : next) {
        if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= dims.x() || n[1] >= dims.y() || n[2] >= dims.z()) continue;
        const int m = L.cube_index(n[0], n[1], n[2]);
        if (touched[static_cast<std::size_t>(m)] || region[static_cast<std::size_t>(m)] >= 0) continue;
        region[static_cast<std::size_t>(m)] = r;
        stack.push_back(m);
      }
    }
  }
  const int regions = static_cast<int>(seed.size());
  std::vector<unsigned char> inside(seed.size(), 0);
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) if (regions > 1)
  for (int r = 0; r < regions; ++r) {
    errors.run(r, [&] {
      const int c = seed[static_cast<std::size_t>(r)];
      const int i = c % dims.x(), j = (c / dims.x()) % dims.y(), k = c / (dims.x() * dims.y());
      const Eigen::Vector3d centre = L.origin + L.spacing * Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5);
      inside[static_cast<std::size_t>(r)] = std::abs(winding_number(V, F, centre)) > 0.5 ? 1 : 0;
    });
  }
  errors.rethrow();
  std::vector<unsigned char> out(n_cubes, 0);
  for (std::size_t c = 0; c < n_cubes; ++c)
    if (!touched[c]) out[c] = inside[static_cast<std::size_t>(region[c])];
  return out;
}

/// The hex mesh of the kept cubes: cells in grid order, and the grid nodes they use, numbered in grid order.
void build_cells(Lattice& L, const std::vector<unsigned char>& keep) {
  const Eigen::Vector3i& dims = L.dims;
  const std::size_t n_cubes = keep.size();
  L.cell_at.assign(n_cubes, -1);
  int cells = 0;
  for (std::size_t c = 0; c < n_cubes; ++c)
    if (keep[c]) L.cell_at[c] = cells++;
  const Eigen::Vector3i nd = dims + Eigen::Vector3i::Ones();
  const auto node_index = [&](int i, int j, int k) {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(nd.x()) * (static_cast<std::size_t>(j) +
                                                                            static_cast<std::size_t>(nd.y()) * k);
  };
  const auto corner = [&](int c, int a) {  // grid node of corner a of cube c, VolumeMesh's corner order
    const int i = c % dims.x(), j = (c / dims.x()) % dims.y(), k = c / (dims.x() * dims.y());
    return node_index(i + (a & 1), j + ((a >> 1) & 1), k + ((a >> 2) & 1));
  };
  std::vector<int> node(static_cast<std::size_t>(nd.x()) * nd.y() * nd.z(), -1);
  for (std::size_t c = 0; c < n_cubes; ++c)
    if (L.cell_at[c] >= 0)
      for (int a = 0; a < 8; ++a) node[corner(static_cast<int>(c), a)] = 0;
  int vertices = 0;
  for (int& n : node)
    if (n == 0) n = vertices++;

  L.mesh.type = CellType::hex8;
  L.mesh.vertices.resize(3, vertices);
  for (int k = 0; k < nd.z(); ++k)
    for (int j = 0; j < nd.y(); ++j)
      for (int i = 0; i < nd.x(); ++i)
        if (const int n = node[node_index(i, j, k)]; n >= 0)
          L.mesh.vertices.col(n) = L.origin + L.spacing * Eigen::Vector3d(i, j, k);
  L.mesh.cells.resize(8, cells);
  for (std::size_t c = 0; c < n_cubes; ++c)
    if (const int cell = L.cell_at[c]; cell >= 0)
      for (int a = 0; a < 8; ++a) L.mesh.cells(a, cell) = node[corner(static_cast<int>(c), a)];
}

}  // namespace

Lattice lattice_for_surface(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution) {
  if (resolution < 1) throw std::invalid_argument(fmt::format("lattice resolution must be >= 1, got {}", resolution));
  if (F.cols() == 0) throw std::invalid_argument("lattice of a surface with no triangles");
  check_triangles(V, F);
  Lattice L = empty_grid(V, F, resolution);
  // Every cube a triangle meets (exact separating-axis tests), and every cube wholly inside.
  std::vector<unsigned char> keep = touched_cubes(L, V, F);
  const std::vector<unsigned char> inside = inside_cubes(L, V, F, keep, edge_counts(F).open > 0);
  for (std::size_t c = 0; c < keep.size(); ++c) keep[c] = keep[c] || inside[c];
  build_cells(L, keep);
  return L;
}

}  // namespace snh
