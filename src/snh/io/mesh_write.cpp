#include "snh/io/mesh_write.hpp"

#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "snh/io/atomic_file.hpp"
#include "snh/io/vtu.hpp"

namespace snh {
namespace {

/// VolumeMesh lattice corner order → the bottom-face-around order of Gmsh, MEDIT and VTK hexahedra.
constexpr int kHexToFileOrder[8] = {0, 1, 3, 2, 4, 5, 7, 6};

int file_corner(CellType t, int a) { return t == CellType::tet4 ? a : kHexToFileOrder[a]; }

}  // namespace

void write_msh(const std::filesystem::path& path, const VolumeMesh& m) {
  write_atomically(path, [&](std::ostream& o) {
    const Eigen::Index nv = m.vertex_count(), nc = m.cell_count();
    const int n = nodes_per_cell(m.type);
    fmt::print(o, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {} 1 {}\n3 1 0 {}\n", nv, nv, nv);
    for (Eigen::Index v = 0; v < nv; ++v) fmt::print(o, "{}\n", v + 1);
    for (Eigen::Index v = 0; v < nv; ++v) fmt::print(o, "{:.17g} {:.17g} {:.17g}\n", m.vertices(0, v), m.vertices(1, v), m.vertices(2, v));
    fmt::print(o, "$EndNodes\n$Elements\n1 {} 1 {}\n3 1 {} {}\n", nc, nc, m.type == CellType::tet4 ? 4 : 5, nc);
    for (Eigen::Index c = 0; c < nc; ++c) {
      fmt::print(o, "{}", c + 1);
      for (int a = 0; a < n; ++a) fmt::print(o, " {}", m.cells(file_corner(m.type, a), c) + 1);
      o << '\n';
    }
    o << "$EndElements\n";
  });
}

void write_medit(const std::filesystem::path& path, const VolumeMesh& m) {
  write_atomically(path, [&](std::ostream& o) {
    const int n = nodes_per_cell(m.type);
    fmt::print(o, "MeshVersionFormatted 2\nDimension 3\nVertices\n{}\n", m.vertex_count());
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      fmt::print(o, "{:.17g} {:.17g} {:.17g} 0\n", m.vertices(0, v), m.vertices(1, v), m.vertices(2, v));
    fmt::print(o, "{}\n{}\n", m.type == CellType::tet4 ? "Tetrahedra" : "Hexahedra", m.cell_count());
    for (Eigen::Index c = 0; c < m.cell_count(); ++c) {
      for (int a = 0; a < n; ++a) fmt::print(o, "{} ", m.cells(file_corner(m.type, a), c) + 1);
      o << "0\n";
    }
    o << "End\n";
  });
}

void check_writable_mesh_format(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext != ".msh" && ext != ".vtu" && ext != ".mesh")
    throw std::invalid_argument(fmt::format("{}: cannot write '{}' meshes (known: .msh, .vtu, .mesh)", path.string(), ext));
}

void write_mesh(const std::filesystem::path& path, const VolumeMesh& mesh) {
  check_writable_mesh_format(path);
  const std::string ext = path.extension().string();
  if (ext == ".msh") write_msh(path, mesh);
  else if (ext == ".mesh") write_medit(path, mesh);
  else write_vtu(path, mesh, mesh.vertices, {}, {});
}

}  // namespace snh
