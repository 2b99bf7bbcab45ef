#include "snh/io/tetgen.hpp"

#include <cmath>
#include <vector>

#include <fmt/format.h>

#include "snh/io/lexer.hpp"
#include "snh/io/mesh_builder.hpp"

namespace snh {

MeshFile read_tetgen(const std::filesystem::path& node_path, const std::filesystem::path& ele_path) {
  detail::MeshBuilder b;
  detail::Lexer nodes = detail::Lexer::open(node_path, detail::text_head(node_path, '#'), '#');
  const long long n = nodes.count("the number of vertices");
  const long long dim = nodes.integer("the dimension");
  if (dim != 3) nodes.fail(fmt::format("only 3D .node files are supported, got dimension {}", dim));
  const long long attributes = nodes.count("the number of attributes", 1000);
  const long long markers = nodes.count("the boundary-marker flag", 1);
  for (long long i = 0; i < n; ++i) {
    const long long id = nodes.integer("a vertex index");
    const double x = nodes.number("x"), y = nodes.number("y"), z = nodes.number("z");
    for (long long a = 0; a < attributes + markers; ++a) (void)nodes.number("a vertex attribute");
    b.vertex(nodes, id, x, y, z);
  }
  if (!nodes.at_end()) nodes.fail(fmt::format("more data than the {} vertices the header announces", n), nodes.line() + 1);

  detail::Lexer ele = detail::Lexer::open(ele_path, detail::text_head(ele_path, '#'), '#');
  const long long m = ele.count("the number of tetrahedra");
  const long long per = ele.integer("the nodes per tetrahedron");
  if (per != 4) ele.fail(fmt::format("only linear tetrahedra (4 nodes) are supported, got {} nodes", per));
  const long long region = ele.count("the region-attribute flag", 1);
  for (long long i = 0; i < m; ++i) {
    (void)ele.integer("a tetrahedron index");
    const int line = ele.line();
    std::vector<long long> ids(4);
    for (auto& id : ids) id = ele.integer("a vertex index");
    // TetGen writes region attributes as numbers; a whole one is the region's tag, any other none (0).
    double attribute = 0.0;
    if (region) attribute = ele.number("a region attribute");
    const bool whole = attribute == std::round(attribute) && std::abs(attribute) < 9e15;
    b.cell(ele, CellType::tet4, ids, line, whole ? static_cast<long long>(attribute) : 0);
  }
  if (!ele.at_end()) ele.fail(fmt::format("more data than the {} tetrahedra the header announces", m), ele.line() + 1);
  return b.finish(ele);
}

}  // namespace snh
