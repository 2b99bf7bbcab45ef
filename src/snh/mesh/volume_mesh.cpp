#include "snh/mesh/volume_mesh.hpp"

namespace snh {

double cell_volume(const VolumeMesh& m, Eigen::Index c) {
  const auto X = [&](int a) -> Eigen::Vector3d { return m.vertices.col(m.cells(a, c)); };
  if (m.type == CellType::tet4) {
    Eigen::Matrix3d D;
    D << X(1) - X(0), X(2) - X(0), X(3) - X(0);
    return D.determinant() / 6.0;
  }
  // Twice the Jacobian at the centre (on [−1, 1]³), so its determinant is 8 det J, the volume of a
  // parallelepiped; for other hexes the volume at the centre, not the exact one (rest_state's 2×2×2 rule is).
  Eigen::Matrix3d J;
  J.col(0) = 0.25 * (X(1) - X(0) + X(3) - X(2) + X(5) - X(4) + X(7) - X(6));
  J.col(1) = 0.25 * (X(2) - X(0) + X(3) - X(1) + X(6) - X(4) + X(7) - X(5));
  J.col(2) = 0.25 * (X(4) - X(0) + X(5) - X(1) + X(6) - X(2) + X(7) - X(3));
  return J.determinant();
}

double mesh_volume(const VolumeMesh& m) {
  double sum = 0.0;
  for (Eigen::Index c = 0; c < m.cell_count(); ++c) sum += cell_volume(m, c);
  return sum;
}

}  // namespace snh
