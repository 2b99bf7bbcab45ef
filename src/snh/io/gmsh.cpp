#include "snh/io/gmsh.hpp"

#include <cmath>
#include <cstdint>
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
namespace {

using detail::Lexer;
using detail::MeshBuilder;

/// The nodes of a Gmsh element type: those kept (4: 4-node tet, 5: 8-node hex) and those skipped; -1
/// for a type not known here.
int gmsh_nodes(long long type) {
  switch (type) {
    case 15: return 1;  // point
    case 1: return 2;   // line
    case 2: return 3;   // triangle
    case 3: return 4;   // quadrangle
    case 4: return 4;   // tetrahedron
    case 5: return 8;   // hexahedron
    case 6: return 6;   // prism
    case 7: return 5;   // pyramid
    default: return -1;
  }
}

/// Adds an element of Gmsh type `type` with file node tags `ids` and region tag `tag`: a tet or hex cell, an
/// error for a prism or pyramid, nothing for a lower-dimensional element.
void gmsh_cell(Lexer& lx, MeshBuilder& b, long long type, const std::vector<long long>& ids, int line, long long tag) {
  if (type == 4) b.cell(lx, CellType::tet4, ids, line, tag);
  else if (type == 5) b.cell(lx, CellType::hex8, detail::hex_to_lattice(ids), line, tag);
  else if (type == 6 || type == 7)
    lx.fail(fmt::format("{} cells are not supported (tets or hexes only)", type == 6 ? "prism" : "pyramid"), line);
}

/// Reads the word that closes `section` ("$EndNodes", ...).
void expect_end(Lexer& lx, const char* section) {
  const std::string_view t = lx.word(section);
  if (t != section) lx.fail(fmt::format("expected {}, got '{}' (wrong count before it?)", section, t));
}

/// `v`, or an error when it is inf or nan (binary coordinates do not pass through Lexer::number).
double finite(Lexer& lx, double v, const char* what) {
  if (!std::isfinite(v)) lx.fail(fmt::format("{} is not finite", what));
  return v;
}

/// $Nodes or $Elements of a binary 4.1 file (the section name just read; the data follows its line).
void read_gmsh41_binary_section(Lexer& lx, MeshBuilder& b, std::string_view section) {
  lx.begin_binary();
  const int line = lx.line();
  if (section == "$Nodes") {
    const auto blocks = lx.raw<std::uint64_t>("the number of entity blocks");
    (void)lx.raw<std::uint64_t>("the number of nodes");
    (void)lx.raw<std::uint64_t>("the smallest node tag");
    (void)lx.raw<std::uint64_t>("the largest node tag");
    for (std::uint64_t k = 0; k < blocks; ++k) {
      (void)lx.raw<std::int32_t>("the entity dimension");
      (void)lx.raw<std::int32_t>("the entity tag");
      if (lx.raw<std::int32_t>("the parametric flag") != 0) lx.fail("parametric node coordinates are not supported", line);
      const auto n = lx.raw<std::uint64_t>("the nodes in the block");
      if (n > lx.remaining() / 32) lx.fail(fmt::format("{} nodes announced, more than the file holds", n), line);
      std::vector<std::uint64_t> tags(n);
      for (auto& t : tags) t = lx.raw<std::uint64_t>("a node tag");
      for (std::uint64_t i = 0; i < n; ++i) {
        const double x = finite(lx, lx.raw<double>("x"), "a coordinate"), y = finite(lx, lx.raw<double>("y"), "a coordinate"),
                     z = finite(lx, lx.raw<double>("z"), "a coordinate");
        b.vertex(lx, static_cast<long long>(tags[i]), x, y, z);
      }
    }
    return;
  }
  const auto blocks = lx.raw<std::uint64_t>("the number of entity blocks");
  (void)lx.raw<std::uint64_t>("the number of elements");
  (void)lx.raw<std::uint64_t>("the smallest element tag");
  (void)lx.raw<std::uint64_t>("the largest element tag");
  for (std::uint64_t k = 0; k < blocks; ++k) {
    (void)lx.raw<std::int32_t>("the entity dimension");
    const auto entity = lx.raw<std::int32_t>("the entity tag");
    const auto type = lx.raw<std::int32_t>("the element type");
    const int nodes = gmsh_nodes(type);
    if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type), line);
    const auto n = lx.raw<std::uint64_t>("the elements in the block");
    if (n > (1ULL << 31)) lx.fail(fmt::format("implausible element count {} in a block", n), line);
    for (std::uint64_t i = 0; i < n; ++i) {
      (void)lx.raw<std::uint64_t>("an element tag");
      std::vector<long long> ids(nodes);
      for (auto& id : ids) id = static_cast<long long>(lx.raw<std::uint64_t>("a node tag"));
      gmsh_cell(lx, b, type, ids, line, entity);
    }
  }
}

/// $Nodes or $Elements of a binary 2.2 file: a text count line, then the records.
void read_gmsh22_binary_section(Lexer& lx, MeshBuilder& b, std::string_view section) {
  const long long n = lx.count(section == "$Nodes" ? "the number of nodes" : "the number of elements");
  lx.begin_binary();
  const int line = lx.line();
  if (section == "$Nodes") {
    for (long long i = 0; i < n; ++i) {
      const auto id = lx.raw<std::int32_t>("a node tag");
      const double x = finite(lx, lx.raw<double>("x"), "a coordinate"), y = finite(lx, lx.raw<double>("y"), "a coordinate"),
                   z = finite(lx, lx.raw<double>("z"), "a coordinate");
      b.vertex(lx, id, x, y, z);
    }
    return;
  }
  for (long long read = 0; read < n;) {
    const auto type = lx.raw<std::int32_t>("an element type");
    const auto count = lx.raw<std::int32_t>("the elements that follow");
    const auto tags = lx.raw<std::int32_t>("the number of tags");
    const int nodes = gmsh_nodes(type);
    if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type), line);
    if (count <= 0 || count > n - read || tags < 0 || tags > 100) lx.fail("corrupt binary element header", line);
    for (int i = 0; i < count; ++i) {
      (void)lx.raw<std::int32_t>("an element tag");
      long long physical = 0;  // the first tag
      for (int t = 0; t < tags; ++t) {
        const auto v = lx.raw<std::int32_t>("a tag");
        if (t == 0) physical = v;
      }
      std::vector<long long> ids(nodes);
      for (auto& id : ids) id = lx.raw<std::int32_t>("a node tag");
      gmsh_cell(lx, b, type, ids, line, physical);
    }
    read += count;
  }
}

/// $Nodes of an ASCII file (the section name just read), up to its $EndNodes.
void read_ascii_nodes(Lexer& lx, MeshBuilder& b, bool v2) {
  if (v2) {
    const long long n = lx.count("the number of nodes");
    for (long long i = 0; i < n; ++i) {
      const long long id = lx.integer("a node tag");
      const double x = lx.number("x"), y = lx.number("y"), z = lx.number("z");
      b.vertex(lx, id, x, y, z);
    }
    return;
  }
  const long long blocks = lx.count("the number of entity blocks");
  (void)lx.count("the number of nodes");
  (void)lx.integer("the smallest node tag");
  (void)lx.integer("the largest node tag");
  for (long long k = 0; k < blocks; ++k) {
    (void)lx.integer("the entity dimension");
    (void)lx.integer("the entity tag");
    const long long parametric = lx.count("the parametric flag", 1);
    const long long n = lx.count("the nodes in the block");
    if (static_cast<std::size_t>(n) > lx.remaining()) lx.fail(fmt::format("{} nodes announced, more than the file holds", n));
    std::vector<long long> tags(n);
    for (auto& t : tags) t = lx.integer("a node tag");
    for (long long i = 0; i < n; ++i) {
      const double x = lx.number("x"), y = lx.number("y"), z = lx.number("z");
      if (parametric) lx.fail("parametric node coordinates are not supported");
      b.vertex(lx, tags[i], x, y, z);
    }
  }
}

/// $Elements of an ASCII file (the section name just read), up to its $EndElements.
void read_ascii_elements(Lexer& lx, MeshBuilder& b, bool v2) {
  if (v2) {
    const long long n = lx.count("the number of elements");
    for (long long i = 0; i < n; ++i) {
      (void)lx.integer("an element tag");
      const int line = lx.line();
      const long long type = lx.integer("an element type");
      const int nodes = gmsh_nodes(type);
      if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type));
      const long long tags = lx.count("the number of tags", 100);
      long long physical = 0;  // the first tag
      for (long long t = 0; t < tags; ++t) {
        const long long v = lx.integer("a tag");
        if (t == 0) physical = v;
      }
      std::vector<long long> ids(nodes);
      for (auto& id : ids) id = lx.integer("a node tag");
      gmsh_cell(lx, b, type, ids, line, physical);
    }
    return;
  }
  const long long blocks = lx.count("the number of entity blocks");
  (void)lx.count("the number of elements");
  (void)lx.integer("the smallest element tag");
  (void)lx.integer("the largest element tag");
  for (long long k = 0; k < blocks; ++k) {
    (void)lx.integer("the entity dimension");
    const long long entity = lx.integer("the entity tag");
    const long long type = lx.integer("the element type");
    const int nodes = gmsh_nodes(type);
    if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type));
    const long long n = lx.count("the elements in the block");
    for (long long i = 0; i < n; ++i) {
      (void)lx.integer("an element tag");
      const int line = lx.line();
      std::vector<long long> ids(nodes);
      for (auto& id : ids) id = lx.integer("a node tag");
      gmsh_cell(lx, b, type, ids, line, entity);
    }
  }
}

}  // namespace

MeshFile read_gmsh(const std::filesystem::path& path) {
  Lexer lx = Lexer::open(path, detail::text_head(path, '\0', "$MeshFormat", "a Gmsh file"));
  if (lx.word("$MeshFormat") != "$MeshFormat") lx.fail("not a Gmsh file: it must start with $MeshFormat");
  const std::string_view version = lx.word("the format version");
  const long long file_type = lx.integer("the file type");
  const long long data_size = lx.integer("the data size");
  const bool v2 = version.substr(0, 2) == "2.", v4 = version == "4.1";
  if (!v2 && !v4) lx.fail(fmt::format("unsupported .msh version {} (2.2 and 4.1 are)", version));
  if (file_type != 0 && file_type != 1) lx.fail(fmt::format("unknown file type {} (0 ASCII, 1 binary)", file_type));
  const bool binary = file_type == 1;
  if (binary) {
    if (data_size != 8) lx.fail(fmt::format("binary files with data size {} are not supported (8 is)", data_size));
    lx.begin_binary();
    if (lx.raw<std::int32_t>("the endianness check") != 1) lx.fail("a big-endian binary file is not supported");
  }
  expect_end(lx, "$EndMeshFormat");
  MeshBuilder b;
  bool nodes_seen = false, elements_seen = false;
  for (;;) {
    const std::string_view section = lx.next();
    if (section.empty()) break;
    if ((section == "$Nodes" || section == "$Elements") && binary) {
      if (section == "$Elements" && !nodes_seen) lx.fail("$Elements before $Nodes");
      (section == "$Nodes" ? nodes_seen : elements_seen) = true;
      if (v4) read_gmsh41_binary_section(lx, b, section);
      else read_gmsh22_binary_section(lx, b, section);
      expect_end(lx, section == "$Nodes" ? "$EndNodes" : "$EndElements");
    } else if (section == "$Nodes") {
      nodes_seen = true;
      read_ascii_nodes(lx, b, v2);
      expect_end(lx, "$EndNodes");
    } else if (section == "$Elements") {
      elements_seen = true;
      if (!nodes_seen) lx.fail("$Elements before $Nodes");
      read_ascii_elements(lx, b, v2);
      expect_end(lx, "$EndElements");
    } else if (section.size() > 1 && section[0] == '$') {  // another section: skip to its end
      const std::string end = fmt::format("$End{}", section.substr(1));
      // Binary sections ($Entities, ...) cannot be tokenised: find the end marker in the bytes.
      if (!lx.skip_past(end)) lx.fail(fmt::format("the file ends inside {}", section));
    } else {
      lx.fail(fmt::format("expected a section ($Nodes, $Elements, ...), got '{}'", section));
    }
  }
  if (!nodes_seen || !elements_seen) lx.fail("the file has no $Nodes or no $Elements section");
  return b.finish(lx);
}

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
      for (int a = 0; a < n; ++a) fmt::print(o, " {}", m.cells(detail::file_corner(m.type, a), c) + 1);
      o << '\n';
    }
    o << "$EndElements\n";
  });
}

}  // namespace snh
