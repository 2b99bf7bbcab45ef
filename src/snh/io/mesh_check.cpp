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
  for (Eigen::Index v = 0; v < mesh.vertex_count(); ++v)
    if (!mesh.vertices.col(v).allFinite())
      throw MeshError(fmt::format("{}: vertex {} has a non-finite coordinate", file.string(), v));
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
    if (volume[c] < 0.0) {  // turn it the right way round
      if (mesh.type == CellType::tet4) std::swap(mesh.cells(2, c), mesh.cells(3, c));
      else
        for (int a = 0; a < 4; ++a) std::swap(mesh.cells(a, c), mesh.cells(a + 4, c));
      ++m.reoriented;
    }
  }
}

}  // namespace snh
