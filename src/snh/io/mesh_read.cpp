#include "snh/io/mesh_read.hpp"

#include "snh/io/base64.hpp"
#include "snh/io/lexer.hpp"
#include "snh/io/surface_read.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include <fmt/format.h>

namespace snh {
namespace {

namespace fs = std::filesystem;
using detail::Lexer;
using detail::read_all;
using detail::xml_attribute;

/// Collects vertices and cells of one type; maps file vertex ids to indices.
struct Builder {
  std::vector<double> xyz;
  std::unordered_map<long long, int> index_of;  ///< file id → index (formats with arbitrary ids)
  std::optional<CellType> type;
  std::vector<int> cells;
  std::vector<int> lines;

  void vertex(Lexer& lx, long long id, double x, double y, double z) {
    if (!index_of.emplace(id, static_cast<int>(xyz.size() / 3)).second) lx.fail(fmt::format("vertex {} is defined twice", id));
    xyz.insert(xyz.end(), {x, y, z});
  }
  /// Adds a cell from file ids (already in VolumeMesh corner order).
  void cell(Lexer& lx, CellType t, const std::vector<long long>& ids, int line) {
    if (type && *type != t)
      lx.fail(fmt::format("a mesh of both tets and hexes is not supported (this {} follows {})", t == CellType::tet4 ? "tet" : "hex",
                          *type == CellType::tet4 ? "tets" : "hexes"),
              line);
    type = t;
    for (long long id : ids) {
      const auto it = index_of.find(id);
      if (it == index_of.end()) lx.fail(fmt::format("cell refers to vertex {}, which does not exist", id), line);
      cells.push_back(it->second);
    }
    lines.push_back(line);
  }
  MeshFile finish(const Lexer& lx) {
    if (!type) lx.fail("the file has no tetrahedra or hexahedra");
    MeshFile m;
    m.mesh.type = *type;
    m.mesh.vertices = Eigen::Map<const Eigen::Matrix3Xd>(xyz.data(), 3, static_cast<Eigen::Index>(xyz.size() / 3));
    const int n = nodes_per_cell(*type);
    m.mesh.cells = Eigen::Map<const Eigen::MatrixXi>(cells.data(), n, static_cast<Eigen::Index>(cells.size() / n));
    m.cell_lines = lines;
    return m;
  }
};

/// VTK / Gmsh / MEDIT hexahedron order (bottom face around, then top) ↔ VolumeMesh lattice order.
constexpr int kHexFromVtk[8] = {0, 1, 3, 2, 4, 5, 7, 6};

std::vector<long long> hex_to_lattice(const std::vector<long long>& v) {
  std::vector<long long> out(8);
  for (int a = 0; a < 8; ++a) out[a] = v[kHexFromVtk[a]];
  return out;
}

// ---- TetGen .node / .ele --------------------------------------------------------------------------

MeshFile read_tetgen(const fs::path& node_path, const fs::path& ele_path) {
  Builder b;
  Lexer nodes(node_path, read_all(node_path), '#');
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
  Lexer ele(ele_path, read_all(ele_path), '#');
  const long long m = ele.count("the number of tetrahedra");
  const long long per = ele.integer("the nodes per tetrahedron");
  if (per != 4) ele.fail(fmt::format("only linear tetrahedra (4 nodes) are supported, got {} nodes", per));
  const long long region = ele.count("the region-attribute flag", 1);
  for (long long i = 0; i < m; ++i) {
    (void)ele.integer("a tetrahedron index");
    const int line = ele.line();
    std::vector<long long> v(4);
    for (auto& x : v) x = ele.integer("a vertex index");
    if (region) (void)ele.number("a region attribute");
    b.cell(ele, CellType::tet4, v, line);
  }
  if (!ele.at_end()) ele.fail(fmt::format("more data than the {} tetrahedra the header announces", m), ele.line() + 1);
  return b.finish(ele);
}

// ---- MEDIT .mesh ----------------------------------------------------------------------------------

MeshFile read_medit(const fs::path& path) {
  Lexer lx(path, read_all(path), '#');
  Builder b;
  bool dimension_seen = false;
  // Sections other than vertices, tets and hexes: values per item.
  const std::map<std::string, int, std::less<>> skipped = {
      {"Edges", 3},       {"Triangles", 4},       {"Quadrilaterals", 5}, {"Corners", 1},  {"Ridges", 1},
      {"RequiredVertices", 1}, {"RequiredEdges", 1}, {"RequiredTriangles", 1}, {"Normals", 3}, {"Tangents", 3},
      {"NormalAtVertices", 2}, {"TangentAtVertices", 2}};
  for (;;) {
    const std::string_view key = lx.next();
    if (key.empty() || key == "End") break;
    if (key == "MeshVersionFormatted") {
      const long long v = lx.integer("the format version");
      if (v != 1 && v != 2) lx.fail(fmt::format("unsupported MeshVersionFormatted {}", v));
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
        std::vector<long long> v(tet ? 4 : 8);
        for (auto& x : v) x = lx.integer("a vertex index");
        const int line = lx.line();
        (void)lx.integer("a cell reference");
        b.cell(lx, tet ? CellType::tet4 : CellType::hex8, tet ? v : hex_to_lattice(v), line);
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

// ---- Gmsh .msh 2.2 and 4.1 ------------------------------------------------------------------------

/// Gmsh element types kept (4: 4-node tet, 5: 8-node hex) and the node counts of those skipped.
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

void gmsh_cell(Lexer& lx, Builder& b, long long type, const std::vector<long long>& v, int line) {
  if (type == 4) b.cell(lx, CellType::tet4, v, line);
  else if (type == 5) b.cell(lx, CellType::hex8, hex_to_lattice(v), line);
  else if (type == 6 || type == 7)
    lx.fail(fmt::format("{} cells are not supported (tets or hexes only)", type == 6 ? "prism" : "pyramid"), line);
}

void expect_end(Lexer& lx, const char* section) {
  const std::string_view t = lx.word(section);
  if (t != section) lx.fail(fmt::format("expected {}, got '{}' (wrong count before it?)", section, t));
}

double finite(Lexer& lx, double v, const char* what) {
  if (!std::isfinite(v)) lx.fail(fmt::format("{} is not finite", what));
  return v;
}

/// $Nodes or $Elements of a binary 4.1 file (the section name just read; the data follows its line).
void read_gmsh41_binary_section(Lexer& lx, Builder& b, std::string_view section) {
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
  } else {
    const auto blocks = lx.raw<std::uint64_t>("the number of entity blocks");
    (void)lx.raw<std::uint64_t>("the number of elements");
    (void)lx.raw<std::uint64_t>("the smallest element tag");
    (void)lx.raw<std::uint64_t>("the largest element tag");
    for (std::uint64_t k = 0; k < blocks; ++k) {
      (void)lx.raw<std::int32_t>("the entity dimension");
      (void)lx.raw<std::int32_t>("the entity tag");
      const auto type = lx.raw<std::int32_t>("the element type");
      const int nodes = gmsh_nodes(type);
      if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type), line);
      const auto n = lx.raw<std::uint64_t>("the elements in the block");
      if (n > (1ULL << 31)) lx.fail(fmt::format("implausible element count {} in a block", n), line);
      for (std::uint64_t i = 0; i < n; ++i) {
        (void)lx.raw<std::uint64_t>("an element tag");
        std::vector<long long> v(nodes);
        for (auto& x : v) x = static_cast<long long>(lx.raw<std::uint64_t>("a node tag"));
        gmsh_cell(lx, b, type, v, line);
      }
    }
  }
}

/// Gmsh 2.2 binary: a text count line, then the records.
void read_gmsh22_binary_section(Lexer& lx, Builder& b, std::string_view section) {
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
      for (int t = 0; t < tags; ++t) (void)lx.raw<std::int32_t>("a tag");
      std::vector<long long> v(nodes);
      for (auto& x : v) x = lx.raw<std::int32_t>("a node tag");
      gmsh_cell(lx, b, type, v, line);
    }
    read += count;
  }
}

MeshFile read_gmsh(const fs::path& path) {
  Lexer lx(path, read_all(path));
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
  Builder b;
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
      if (v2) {
        const long long n = lx.count("the number of nodes");
        for (long long i = 0; i < n; ++i) {
          const long long id = lx.integer("a node tag");
          const double x = lx.number("x"), y = lx.number("y"), z = lx.number("z");
          b.vertex(lx, id, x, y, z);
        }
      } else {
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
      expect_end(lx, "$EndNodes");
    } else if (section == "$Elements") {
      elements_seen = true;
      if (!nodes_seen) lx.fail("$Elements before $Nodes");
      if (v2) {
        const long long n = lx.count("the number of elements");
        for (long long i = 0; i < n; ++i) {
          (void)lx.integer("an element tag");
          const int line = lx.line();
          const long long type = lx.integer("an element type");
          const int nodes = gmsh_nodes(type);
          if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type));
          const long long tags = lx.count("the number of tags", 100);
          for (long long t = 0; t < tags; ++t) (void)lx.integer("a tag");
          std::vector<long long> v(nodes);
          for (auto& x : v) x = lx.integer("a node tag");
          gmsh_cell(lx, b, type, v, line);
        }
      } else {
        const long long blocks = lx.count("the number of entity blocks");
        (void)lx.count("the number of elements");
        (void)lx.integer("the smallest element tag");
        (void)lx.integer("the largest element tag");
        for (long long k = 0; k < blocks; ++k) {
          (void)lx.integer("the entity dimension");
          (void)lx.integer("the entity tag");
          const long long type = lx.integer("the element type");
          const int nodes = gmsh_nodes(type);
          if (nodes < 0) lx.fail(fmt::format("unsupported element type {} (tets or hexes only)", type));
          const long long n = lx.count("the elements in the block");
          for (long long i = 0; i < n; ++i) {
            (void)lx.integer("an element tag");
            const int line = lx.line();
            std::vector<long long> v(nodes);
            for (auto& x : v) x = lx.integer("a node tag");
            gmsh_cell(lx, b, type, v, line);
          }
        }
      }
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

// ---- VTK .vtu (ASCII data arrays) -----------------------------------------------------------------

/// Reads `count` little-endian values of VTK type `type` from bytes, as doubles; nullopt for an unknown type.
std::optional<std::vector<double>> decode_values(std::string_view type, const char* bytes, std::size_t count) {
  std::vector<double> out(count);
  auto take = [&](auto tag) {
    using T = decltype(tag);
    for (std::size_t i = 0; i < count; ++i) {
      T v;
      std::memcpy(&v, bytes + i * sizeof(T), sizeof(T));
      out[i] = static_cast<double>(v);
    }
  };
  if (type == "Float64") take(double{});
  else if (type == "Float32") take(float{});
  else if (type == "Int64") take(std::int64_t{});
  else if (type == "UInt64") take(std::uint64_t{});
  else if (type == "Int32") take(std::int32_t{});
  else if (type == "UInt32") take(std::uint32_t{});
  else if (type == "Int16") take(std::int16_t{});
  else if (type == "UInt16") take(std::uint16_t{});
  else if (type == "Int8") take(std::int8_t{});
  else if (type == "UInt8") take(std::uint8_t{});
  else return std::nullopt;
  return out;
}

std::size_t vtk_type_size(std::string_view type) {
  if (type == "Float64" || type == "Int64" || type == "UInt64") return 8;
  if (type == "Float32" || type == "Int32" || type == "UInt32") return 4;
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int8" || type == "UInt8") return 1;
  return 0;
}

/// Reads a .vtu file's mesh; when `data` is given, also every named array of <PointData> and <CellData>.
MeshFile read_vtu(const fs::path& path, VtuData* data = nullptr) {
  const std::string text = read_all(path);
  const std::string file = path.string();
  auto line_of = [&](std::size_t pos) {
    return 1 + static_cast<int>(std::count(text.begin(), text.begin() + std::min(pos, text.size()), '\n'));
  };
  auto fail = [&](std::size_t pos, const std::string& what) -> void {
    throw MeshError(fmt::format("{}:{}: {}", file, line_of(pos), what));
  };
  const std::size_t root = text.find("<VTKFile");
  if (root == std::string::npos || text.find("UnstructuredGrid") == std::string::npos)
    fail(0, "not a VTK UnstructuredGrid (.vtu) file");
  const std::string_view root_tag = std::string_view(text).substr(root, text.find('>', root) - root);
  if (const std::string c = xml_attribute(root_tag, "compressor"); !c.empty())
    fail(root, fmt::format("compressed data ({}) is not supported: write the file uncompressed", c));
  if (xml_attribute(root_tag, "byte_order") == "BigEndian") fail(root, "big-endian data is not supported");
  const std::string header_type = xml_attribute(root_tag, "header_type");
  const std::size_t header_size = header_type == "UInt64" ? 8 : 4;
  if (!header_type.empty() && header_type != "UInt32" && header_type != "UInt64")
    fail(root, fmt::format("unknown header_type \"{}\"", header_type));
  // The appended data: what follows the underscore, raw or base64.
  std::string_view appended;
  bool appended_base64 = false;
  if (const std::size_t ad = text.find("<AppendedData"); ad != std::string::npos) {
    const std::string_view tag = std::string_view(text).substr(ad, text.find('>', ad) - ad);
    appended_base64 = xml_attribute(tag, "encoding") == "base64";
    const std::size_t underscore = text.find('_', text.find('>', ad));
    if (underscore == std::string::npos) fail(ad, "<AppendedData> without the '_' that starts the data");
    appended = std::string_view(text).substr(underscore + 1);
  }
  const std::size_t piece = text.find("<Piece");
  if (piece == std::string::npos) fail(0, "no <Piece>");
  const std::string_view piece_tag = std::string_view(text).substr(piece, text.find('>', piece) - piece);
  long long n_points = -1, n_cells = -1;
  try {
    n_points = std::stoll(xml_attribute(piece_tag, "NumberOfPoints"));
    n_cells = std::stoll(xml_attribute(piece_tag, "NumberOfCells"));
  } catch (const std::exception&) {
    fail(piece, "<Piece> needs NumberOfPoints and NumberOfCells");
  }
  if (n_points < 0 || n_cells < 0 || n_points > (1LL << 31) || n_cells > (1LL << 31)) fail(piece, "implausible point or cell count");
  // The values of the DataArray named `name` inside `section` (or its first one), `expected` of them.
  auto array = [&](const char* section, const char* name, long long expected, std::size_t& where) {
    const std::size_t sec = text.find(fmt::format("<{}", section), piece);
    if (sec == std::string::npos) fail(piece, fmt::format("no <{}> section", section));
    const std::size_t sec_end = text.find(fmt::format("</{}", section), sec);
    std::size_t at = sec;
    for (;;) {
      at = text.find("<DataArray", at + 1);
      if (at == std::string::npos || at > sec_end) fail(sec, fmt::format("no DataArray {} in <{}>", name ? name : "", section));
      const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
      if (name && xml_attribute(tag, "Name") != name) continue;
      where = at;
      const std::string label = name ? name : section;
      const std::string format = xml_attribute(tag, "format"), type = xml_attribute(tag, "type");
      if (format == "ascii") {
        const std::size_t start = text.find('>', at) + 1, end = text.find("</DataArray>", start);
        if (end == std::string::npos) fail(at, "unterminated DataArray");
        std::vector<double> out;
        Lexer lx(path, text.substr(start, end - start));
        const bool data_array = std::strcmp(section, "PointData") == 0 || std::strcmp(section, "CellData") == 0;
        while (!lx.at_end()) out.push_back(lx.number(label.c_str(), !data_array));
        if (static_cast<long long>(out.size()) != expected)
          fail(at, fmt::format("{} has {} values, expected {}", label, out.size(), expected));
        return out;
      }
      const std::size_t size = vtk_type_size(type);
      if (size == 0) fail(at, fmt::format("DataArray {} has unknown type \"{}\"", label, type));
      std::string bytes;
      if (format == "binary") {
        const std::size_t start = text.find('>', at) + 1, end = text.find("</DataArray>", start);
        if (end == std::string::npos) fail(at, "unterminated DataArray");
        if (!base64_decode(std::string_view(text).substr(start, end - start), bytes)) fail(at, fmt::format("DataArray {}: invalid base64", label));
      } else if (format == "appended") {
        if (appended.empty()) fail(at, fmt::format("DataArray {} is appended, but the file has no <AppendedData>", label));
        std::size_t offset = 0;
        try {
          offset = std::stoull(xml_attribute(tag, "offset"));
        } catch (const std::exception&) {
          fail(at, fmt::format("DataArray {} is appended but has no offset", label));
        }
        if (offset >= appended.size()) fail(at, fmt::format("DataArray {}: offset {} is past the end of the appended data", label, offset));
        if (appended_base64) {
          // Base64: the header, then the data, each its own stream; decode enough characters for both.
          const std::size_t chars = 4 * ((header_size + 2) / 3) + 4 * ((static_cast<std::size_t>(expected) * size + 2) / 3);
          if (!base64_decode(appended.substr(offset, chars), bytes)) fail(at, fmt::format("DataArray {}: invalid base64", label));
        } else {
          bytes = std::string(appended.substr(offset, header_size + static_cast<std::size_t>(expected) * size));
        }
      } else {
        fail(at, fmt::format("DataArray {} has unknown format \"{}\"", label, format));
      }
      if (bytes.size() < header_size) fail(at, fmt::format("DataArray {}: the data ends before its length header", label));
      std::uint64_t length = 0;
      std::memcpy(&length, bytes.data(), header_size);  // little-endian: the low bytes come first
      if (length != static_cast<std::uint64_t>(expected) * size || bytes.size() < header_size + length)
        fail(at, fmt::format("DataArray {}: {} bytes of data, expected {} ({} values of {})", label,
                             std::min<std::uint64_t>(length, bytes.size() - header_size), expected * size, expected, type));
      std::vector<double> out = *decode_values(type, bytes.data() + header_size, static_cast<std::size_t>(expected));
      if (std::strcmp(section, "Points") == 0)
        for (double v : out)
          if (!std::isfinite(v)) fail(at, "a point coordinate is not finite");
      return out;
    }
  };
  std::size_t where = 0;
  const std::vector<double> points = array("Points", nullptr, 3 * n_points, where);
  Builder b;
  Lexer dummy(path, "");
  for (long long i = 0; i < n_points; ++i) b.vertex(dummy, i, points[3 * i], points[3 * i + 1], points[3 * i + 2]);
  std::size_t w_off = 0, w_types = 0, w_conn = 0;
  const std::vector<double> offsets = array("Cells", "offsets", n_cells, w_off);
  const std::vector<double> types = array("Cells", "types", n_cells, w_types);
  long long total = n_cells ? static_cast<long long>(offsets.back()) : 0;
  if (total < 0 || total > (1LL << 33)) fail(w_off, "implausible offsets");
  const std::vector<double> conn = array("Cells", "connectivity", total, w_conn);
  long long previous = 0;
  std::vector<long long> kept;  // the tet and hex cells, by index in the file
  for (long long c = 0; c < n_cells; ++c) {
    const long long type = static_cast<long long>(types[c]), end = static_cast<long long>(offsets[c]);
    if (end < previous || end > total) fail(w_off, fmt::format("cell {}: offsets are not increasing", c));
    if (type == 5 || type == 9 || type == 3 || type == 1) {  // surface / line / vertex cells: skipped
      previous = end;
      continue;
    }
    kept.push_back(c);
    const int nodes = type == 10 ? 4 : type == 12 ? 8 : -1;
    if (nodes < 0) fail(w_types, fmt::format("cell {} has unsupported VTK type {} (tets 10 and hexes 12 only)", c, type));
    if (end - previous != nodes) fail(w_off, fmt::format("cell {}: offsets give {} nodes for a {}-node cell", c, end - previous, nodes));
    std::vector<long long> v(nodes);
    for (int a = 0; a < nodes; ++a) v[a] = static_cast<long long>(conn[previous + a]);
    for (long long id : v)
      if (id < 0 || id >= n_points) fail(w_conn, fmt::format("cell {} refers to point {}, which does not exist", c, id));
    b.cell(dummy, nodes == 4 ? CellType::tet4 : CellType::hex8, nodes == 4 ? v : hex_to_lattice(v), 0);
    previous = end;
  }
  if (data) {
    // Every named array of the two data sections, by its NumberOfComponents (1 if not given).
    for (const char* section : {"PointData", "CellData"}) {
      const std::size_t sec = text.find(fmt::format("<{}", section), piece);
      if (sec == std::string::npos) continue;
      const std::size_t sec_end = text.find(fmt::format("</{}", section), sec);
      const bool cells = std::strcmp(section, "CellData") == 0;
      for (std::size_t at = text.find("<DataArray", sec); at != std::string::npos && at < sec_end;
           at = text.find("<DataArray", at + 1)) {
        const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
        const std::string name = xml_attribute(tag, "Name");
        if (name.empty()) continue;
        const std::string nc = xml_attribute(tag, "NumberOfComponents");
        long long components = 1;
        if (!nc.empty()) {
          try {
            components = std::stoll(nc);
          } catch (const std::exception&) {
            components = 0;
          }
          if (components < 1 || components > 9) fail(at, fmt::format("DataArray {}: bad NumberOfComponents \"{}\"", name, nc));
        }
        std::size_t w = 0;
        std::vector<double> values = array(section, name.c_str(), (cells ? n_cells : n_points) * components, w);
        if (cells && static_cast<long long>(kept.size()) != n_cells) {  // only the tet and hex cells' values
          std::vector<double> selected;
          for (long long c : kept)
            selected.insert(selected.end(), values.begin() + c * components, values.begin() + (c + 1) * components);
          values = std::move(selected);
        }
        (cells ? data->cell_data : data->point_data)[name] = std::move(values);
      }
    }
  }
  return b.finish(dummy);
}

double cell_volume(const VolumeMesh& m, Eigen::Index c) {
  const auto X = [&](int a) -> Eigen::Vector3d { return m.vertices.col(m.cells(a, c)); };
  if (m.type == CellType::tet4) {
    Eigen::Matrix3d D;
    D << X(1) - X(0), X(2) - X(0), X(3) - X(0);
    return D.determinant() / 6.0;
  }
  // Trilinear hex, lattice corner order: the Jacobian at the centre times 8 (exact for parallelepipeds).
  Eigen::Matrix3d J;
  J.col(0) = 0.25 * (X(1) - X(0) + X(3) - X(2) + X(5) - X(4) + X(7) - X(6));
  J.col(1) = 0.25 * (X(2) - X(0) + X(3) - X(1) + X(6) - X(4) + X(7) - X(5));
  J.col(2) = 0.25 * (X(4) - X(0) + X(5) - X(1) + X(6) - X(2) + X(7) - X(3));
  return J.determinant();
}

}  // namespace

VtuData read_vtu_data(const fs::path& path) {
  VtuData out;
  out.mesh = read_vtu(path, &out);
  return out;
}

MeshFile read_mesh_file(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".node" || ext == ".ele") {
    fs::path node = path, ele = path;
    node.replace_extension(".node");
    ele.replace_extension(".ele");
    return read_tetgen(node, ele);
  }
  if (ext == ".mesh") return read_medit(path);
  if (ext == ".msh") return read_gmsh(path);
  if (ext == ".vtu") return read_vtu(path);
  if (is_surface_file(path)) return tetrahedralize(read_surface(path), path);
  throw MeshError(fmt::format("{}: unknown mesh format '{}' (known: .node/.ele, .mesh, .msh, .vtu; surfaces .obj, .off, "
                              ".ply, .stl)",
                              path.string(), ext));
}

void check_mesh(MeshFile& m, const fs::path& file) {
  VolumeMesh& mesh = m.mesh;
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

MeshFile read_mesh(const fs::path& path) {
  MeshFile m = read_mesh_file(path);
  check_mesh(m, path);
  return m;
}

}  // namespace snh
