#pragma once
// Closed, outward test surfaces for the embed/ tests: icospheres and the boundaries of box-lattice solids.
#include <cmath>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"

namespace snh::test {

struct Surface {
  Eigen::Matrix3Xd V;
  Eigen::Matrix3Xi F;
};

/// The icosahedron refined `subdivisions` times (each triangle into four, new vertices pushed onto the
/// sphere): 20 · 4^subdivisions triangles, counter-clockwise seen from outside.
inline Surface icosphere(int subdivisions, double radius = 1.0, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& x : v) x.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9},  {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6},  {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> middle;
    const auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      if (const auto it = middle.find(key); it != middle.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      return middle[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = mid(tri[0], tri[1]), b = mid(tri[1], tri[2]), c = mid(tri[2], tri[0]);
      g.insert(g.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    f = std::move(g);
  }
  Surface s;
  s.V.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) s.V.col(static_cast<Eigen::Index>(i)) = centre + radius * v[i];
  s.F.resize(3, static_cast<Eigen::Index>(f.size()));
  for (std::size_t i = 0; i < f.size(); ++i) s.F.col(static_cast<Eigen::Index>(i)) = f[i];
  return s;
}

/// The boundary of the cells (i, j, k) of box_hexes(res) on [−1, 1]³ for which keep(i, j, k) holds, its
/// vertices then mapped by x ↦ A x + b (A with positive determinant keeps it outward).
inline Surface box_solid(int res, const std::function<bool(int, int, int)>& keep,
                         const Eigen::Matrix3d& A = Eigen::Matrix3d::Identity(),
                         const Eigen::Vector3d& b = Eigen::Vector3d::Zero()) {
  VolumeMesh box = box_hexes(res);
  std::vector<int> kept;
  for (int k = 0, c = 0; k < res; ++k)
    for (int j = 0; j < res; ++j)
      for (int i = 0; i < res; ++i, ++c)
        if (keep(i, j, k)) kept.push_back(c);
  Eigen::MatrixXi cells(8, static_cast<Eigen::Index>(kept.size()));
  for (std::size_t c = 0; c < kept.size(); ++c) cells.col(static_cast<Eigen::Index>(c)) = box.cells.col(kept[c]);
  box.cells = cells;
  Surface s;
  s.F = boundary_triangles(box);
  s.V = (A * box.vertices).colwise() + b;
  return s;
}

/// The boundary of the box [lo, hi] (12 triangles).
inline Surface axis_box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const Eigen::Vector3d half = 0.5 * (hi - lo);
  return box_solid(1, [](int, int, int) { return true; }, half.asDiagonal(), lo + half);
}

}  // namespace snh::test
