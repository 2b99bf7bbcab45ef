#include "snh/io/medit.hpp"

#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <fmt/ostream.h>

#include "snh/io/atomic_file.hpp"
#include "snh/io/hex_order.hpp"
#include "snh/io/lexer.hpp"
#include "snh/io/mesh_builder.hpp"

namespace snh {

MeshFile read_medit(const std::filesystem::path& path) {
  detail::Lexer lx = detail::Lexer::open(path, detail::text_head(path, '#'), '#');
  detail::MeshBuilder b;
  bool dimension_seen = false;
  // The sections read past (everything but vertices, tets and hexes), with the values of each item.
  const std::map<std::string, int, std::less<>> skipped = {
      {"Edges", 3},       {"Triangles", 4},       {"Quadrilaterals", 5}, {"Corners", 1},  {"Ridges", 1},
      {"RequiredVertices", 1}, {"RequiredEdges", 1}, {"RequiredTriangles", 1}, {"Normals", 3}, {"Tangents", 3},
      {"NormalAtVertices", 2}, {"TangentAtVertices", 2}};
  for (;;) {
    const std::string_view key = lx.next();
    if (key.empty()) break;
    if (key == "End") {
      detail::expect_file_end(lx, "End");
      break;
    }
    if (key == "MeshVersionFormatted") {
      const long long version = lx.integer("the format version");
      if (version != 1 && version != 2) lx.fail(fmt::format("unsupported MeshVersionFormatted {}", version));
    } else if (key == "Dimension") {
      const long long d = lx.integer("the dimension");
      if (d != 3) lx.fail(fmt::format("only 3D meshes are supported, got Dimension {}", d));
      dimension_seen = true;
    } else if (key == "Vertices") {
      const long long n = lx.count("the number of vertices");
      for (long long i = 0; i < n; ++i) {
        const double x = lx.number("x"), y = lx.number("y"), z = lx.number("z");
        (void)lx.integer("a vertex reference");
        b.vertex(lx, i + 1, x, y, z);
      }
    } else if (key == "Tetrahedra" || key == "Hexahedra") {
      const bool tet = key == "Tetrahedra";
      const long long n = lx.count(tet ? "the number of tetrahedra" : "the number of hexahedra");
      for (long long i = 0; i < n; ++i) {
        std::vector<long long> ids(tet ? 4 : 8);
        for (auto& id : ids) id = lx.integer("a vertex index");
        const int line = lx.line();
        const long long reference = lx.integer("a cell reference");
        b.cell(lx, tet ? CellType::tet4 : CellType::hex8, tet ? ids : detail::hex_to_lattice(ids), line, reference);
      }
    } else if (const auto it = skipped.find(key); it != skipped.end()) {
      const long long n = lx.count("the number of items");
      for (long long i = 0; i < n * it->second; ++i) (void)lx.number("a value");
    } else {
      lx.fail(fmt::format("unknown or unsupported section '{}'", key));
    }
  }
  if (!dimension_seen) lx.fail("no 'Dimension 3' line");
  return b.finish(lx);
}

void write_medit(const std::filesystem::path& path, const VolumeMesh& m) {
  write_atomically(path, [&](std::ostream& o) {
    const int n = nodes_per_cell(m.type);
    fmt::print(o, "MeshVersionFormatted 2\nDimension 3\nVertices\n{}\n", m.vertex_count());
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      fmt::print(o, "{:.17g} {:.17g} {:.17g} 0\n", m.vertices(0, v), m.vertices(1, v), m.vertices(2, v));
    fmt::print(o, "{}\n{}\n", m.type == CellType::tet4 ? "Tetrahedra" : "Hexahedra", m.cell_count());
    for (Eigen::Index c = 0; c < m.cell_count(); ++c) {
      for (int a = 0; a < n; ++a) fmt::print(o, "{} ", m.cells(detail::file_corner(m.type, a), c) + 1);
      o << "0\n";
    }
    o << "End\n";
  });
}

}  // namespace snh
