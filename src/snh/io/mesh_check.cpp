#include "snh/io/mesh_check.hpp"

#include <cmath>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace snh {

void check_mesh(MeshFile& m, const std::filesystem::path& file) {
  VolumeMesh& mesh = m.mesh;
  // "FILE:LINE: cell C" where the cell's line is known, else "FILE: cell C".
  auto where = [&](Eigen::Index c) {
    const int line = c < static_cast<Eigen::Index>(m.cell_lines.size()) ? m.cell_lines[c] : 0;
    return line > 0 ? fmt::format("{}:{}: cell {}", file.string(), line, c) : fmt::format("{}: cell {}", file.string(), c);
  };
  if (mesh.cell_count() == 0) throw MeshError(fmt::format("{}: the mesh has no cells", file.string()));
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v) {
    if (!mesh.vertices.col(v).allFinite())
      throw MeshError(fmt::format("{}: vertex {} has a non-finite coordinate", file.string(), v));
    // Beyond it cell volumes (coordinates cubed) and energies overflow: 1e200 was reported "degenerate
    // (rest volume inf)" or ran with an infinite energy.
    for (int k = 0; k < 3; ++k)
      if (std::abs(mesh.vertices(k, v)) > kMaxCoordinate)
        throw MeshError(fmt::format("{}: vertex {} coordinate {} = {:g} is outside the supported range |x| <= {:g}",
                                    file.string(), v, char('x' + k), mesh.vertices(k, v), kMaxCoordinate));
  }
  std::vector<char> used(mesh.vertex_count(), 0);
  const int n = nodes_per_cell(mesh.type);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int a = 0; a < n; ++a) {
      const int v = mesh.cells(a, c);
      if (v < 0 || v >= mesh.vertex_count())
        throw MeshError(fmt::format("{}: vertex index {} out of range", where(c), v));
      for (int b = 0; b < a; ++b)
        if (mesh.cells(b, c) == v) throw MeshError(fmt::format("{}: vertex {} appears twice", where(c), v));
      used[v] = 1;
    }
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!used[v]) throw MeshError(fmt::format("{}: vertex {} is not used by any cell", file.string(), v));
  Eigen::VectorXd volume(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) volume[c] = cell_volume(mesh, c);
  const double mean = volume.cwiseAbs().mean();
  m.reoriented = 0;
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    if (!(std::abs(volume[c]) > 1e-10 * mean))
      throw MeshError(fmt::format("{}: degenerate (rest volume {:.3g}, the mean is {:.3g})", where(c), volume[c], mean));
    if (mesh.type == CellType::hex8) {
      // The Jacobian at each corner (its three edges) must have the sign of the whole cell: a
      // self-crossing (bow-tie) face or a folded corner passed the centre's volume and then stopped the
      // run with "non-positive Jacobian determinant at Gauss point" and no file named.
      const auto X = [&](int a) -> Eigen::Vector3d { return mesh.vertices.col(mesh.cells(a, c)); };
      for (int a = 0; a < 8; ++a) {
        Eigen::Matrix3d E;
        for (int d = 0; d < 3; ++d) {
          const int bit = 1 << d;
          E.col(d) = X(a | bit) - X(a & ~bit);
        }
        const double corner = E.determinant();
        if (corner * (volume[c] < 0.0 ? -1.0 : 1.0) < -1e-10 * mean)
          throw MeshError(fmt::format(
              "{}: self-crossing (bow-tie) or folded hex: the Jacobian at its corner {} (vertex {}) is {:.3g}, "
              "of the opposite sign to the cell's volume {:.3g}",
              where(c), a, mesh.cells(a, c), corner, volume[c]));
      }
    }
    if (volume[c] < 0.0) {  // turn it the right way round
      if (mesh.type == CellType::tet4) std::swap(mesh.cells(2, c), mesh.cells(3, c));
      else
        for (int a = 0; a < 4; ++a) std::swap(mesh.cells(a, c), mesh.cells(a + 4, c));
      ++m.reoriented;
    }
  }
}

}  // namespace snh
