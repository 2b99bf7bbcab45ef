#include "snh/mesh/box.hpp"

#include <array>
#include <stdexcept>
#include <string>

namespace snh {
namespace {

void check_resolution(int res) {
  if (res < 1) throw std::invalid_argument("box resolution must be >= 1, got " + std::to_string(res));
  if (res > 1000) throw std::invalid_argument("box resolution must be <= 1000, got " + std::to_string(res));
}

/// The eight corner indices c0..c7 of lattice cell (i, j, k).
std::array<int, 8> cell_corners(int res, int i, int j, int k) {
  std::array<int, 8> c{};
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) c[dx + 2 * dy + 4 * dz] = lattice_index(res, i + dx, j + dy, k + dz);
  return c;
}

}  // namespace

Eigen::Matrix3Xd box_lattice(int res) {
  check_resolution(res);
  const int n = res + 1;
  const double h = 2.0 / res;
  Eigen::Matrix3Xd V(3, n * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) V.col(lattice_index(res, i, j, k)) = Eigen::Vector3d(-1 + h * i, -1 + h * j, -1 + h * k);
  return V;
}

VolumeMesh box_hexes(int res) {
  VolumeMesh m;
  m.type = CellType::hex8;
  m.vertices = box_lattice(res);
  m.cells.resize(8, res * res * res);
  int c = 0;
  for (int k = 0; k < res; ++k)
    for (int j = 0; j < res; ++j)
      for (int i = 0; i < res; ++i, ++c) {
        const auto corners = cell_corners(res, i, j, k);
        for (int a = 0; a < 8; ++a) m.cells(a, c) = corners[a];
      }
  return m;
}

VolumeMesh box_tets(int res, TetSplit split) {
  static constexpr int kTemplates[6][4] = {{7, 4, 0, 5}, {7, 6, 0, 4}, {7, 5, 0, 1},
                                           {7, 2, 0, 6}, {7, 1, 0, 3}, {7, 3, 0, 2}};
  VolumeMesh m;
  m.type = CellType::tet4;
  m.vertices = box_lattice(res);
  m.cells.resize(4, 6 * res * res * res);
  int c = 0;
  for (int k = 0; k < res; ++k)
    for (int j = 0; j < res; ++j)
      for (int i = 0; i < res; ++i) {
        const auto corners = cell_corners(res, i, j, k);
        const int flip = split == TetSplit::mirrored
                             ? (2 * i >= res ? 1 : 0) | (2 * j >= res ? 2 : 0) | (2 * k >= res ? 4 : 0)
                             : 0;
        for (const auto& t : kTemplates) {
          Eigen::Vector4i tet(corners[t[0] ^ flip], corners[t[1] ^ flip], corners[t[2] ^ flip], corners[t[3] ^ flip]);
          Eigen::Matrix3d Dm;
          for (int a = 0; a < 3; ++a) Dm.col(a) = m.vertices.col(tet[a + 1]) - m.vertices.col(tet[0]);
          if (Dm.determinant() < 0.0) std::swap(tet[2], tet[3]);
          m.cells.col(c++) = tet;
        }
      }
  return m;
}

}  // namespace snh
