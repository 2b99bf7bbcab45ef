#include "snh/io/vtu.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/io/base64.hpp"
#include "snh/io/hex_order.hpp"
#include "snh/io/lexer.hpp"
#include "snh/io/mesh_builder.hpp"

namespace snh {

static_assert(std::endian::native == std::endian::little, "the .vtu writer writes the machine's bytes as little-endian");

VtuWriter::VtuWriter(const VolumeMesh& mesh) : vertices_(mesh.vertex_count()) {
  const int npc = nodes_per_cell(mesh.type);
  connectivity_.reserve(static_cast<std::size_t>(mesh.cell_count() * npc));
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    for (int a = 0; a < npc; ++a) connectivity_.push_back(mesh.cells(detail::file_corner(mesh.type, a), c));
    offsets_.push_back(static_cast<std::int64_t>(connectivity_.size()));
  }
  types_.assign(static_cast<std::size_t>(mesh.cell_count()), mesh.type == CellType::tet4 ? 10 : 12);  // VTK_TETRA, VTK_HEXAHEDRON
}

void VtuWriter::write(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions,
                      const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
                      const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
                      const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars) const {
  const auto cells = static_cast<Eigen::Index>(types_.size());
  auto check = [&](const std::string& name, Eigen::Index count, Eigen::Index expected) {
    if (count != expected)
      throw std::invalid_argument(fmt::format("{}: the .vtu array {} has {} values, expected {}", path.string(), name, count, expected));
  };
  check("Points", positions.cols(), vertices_);
  // The XML, each DataArray with its offset into the appended data; the arrays themselves, in that order.
  struct Block {
    const void* data;
    std::uint64_t bytes;
  };
  std::vector<Block> blocks;
  std::uint64_t offset = 0;
  fmt::memory_buffer b;
  auto o = std::back_inserter(b);
  auto array = [&](std::string_view attributes, const void* data, std::size_t bytes) {
    fmt::format_to(o, "<DataArray {} format=\"appended\" offset=\"{}\"/>\n", attributes, offset);
    blocks.push_back({data, bytes});
    offset += sizeof(std::uint64_t) + bytes;
  };
  fmt::format_to(o, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
                    "header_type=\"UInt64\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n<Points>\n",
                 vertices_, cells);
  array("type=\"Float64\" NumberOfComponents=\"3\"", positions.data(), sizeof(double) * 3 * vertices_);
  fmt::format_to(o, "</Points>\n<Cells>\n");
  array("type=\"Int64\" Name=\"connectivity\"", connectivity_.data(), sizeof(std::int64_t) * connectivity_.size());
  array("type=\"Int64\" Name=\"offsets\"", offsets_.data(), sizeof(std::int64_t) * offsets_.size());
  array("type=\"UInt8\" Name=\"types\"", types_.data(), types_.size());
  fmt::format_to(o, "</Cells>\n<PointData>\n");
  for (const auto& [name, field] : point_data) {
    check(name, field.cols(), vertices_);
    array(fmt::format("type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\"", name), field.data(), sizeof(double) * 3 * vertices_);
  }
  for (const auto& [name, field] : point_scalars) {
    check(name, field.size(), vertices_);
    array(fmt::format("type=\"Float64\" Name=\"{}\"", name), field.data(), sizeof(double) * vertices_);
  }
  fmt::format_to(o, "</PointData>\n<CellData>\n");
  for (const auto& [name, field] : cell_data) {
    check(name, field.size(), cells);
    array(fmt::format("type=\"Float64\" Name=\"{}\"", name), field.data(), sizeof(double) * cells);
  }
  fmt::format_to(o, "</CellData>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
  write_atomically(path, [&](std::ostream& out) {
    out.write(b.data(), static_cast<std::streamsize>(b.size()));
    for (const Block& block : blocks) {
      out.write(reinterpret_cast<const char*>(&block.bytes), sizeof(block.bytes));
      out.write(static_cast<const char*>(block.data), static_cast<std::streamsize>(block.bytes));
    }
    out << "\n</AppendedData>\n</VTKFile>\n";
  });
}

void write_vtu(const std::filesystem::path& path, const VolumeMesh& mesh, const Eigen::Matrix3Xd& positions,
               const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars) {
  VtuWriter(mesh).write(path, positions, point_data, cell_data, point_scalars);
}

void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& frames,
               const std::vector<std::string>& notes) {
  write_atomically(path, [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n";
    for (std::size_t i = 0; i < frames.size(); ++i) {
      if (i < notes.size() && !notes[i].empty()) {
        std::string note = notes[i];  // "--" may not appear inside an XML comment
        for (auto at = note.find("--"); at != std::string::npos; at = note.find("--", at)) note.erase(at, 1);
        out << "<!-- " << note << " -->\n";
      }
      out << fmt::format("<DataSet timestep=\"{:g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", frames[i].first, frames[i].second);
    }
    out << "</Collection>\n</VTKFile>\n";
  });
}

std::vector<std::pair<double, std::string>> read_pvd(const std::filesystem::path& path) {
  const std::string text = detail::read_all(path);
  std::vector<std::pair<double, std::string>> out;
  for (std::size_t at = text.find("<DataSet"); at != std::string::npos; at = text.find("<DataSet", at + 1)) {
    const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
    const std::string file = detail::xml_attribute(tag, "file"), time = detail::xml_attribute(tag, "timestep");
    double t = static_cast<double>(out.size());
    if (!time.empty()) {
      try {
        t = std::stod(time);
      } catch (const std::exception&) {
        throw MeshError(fmt::format("{}: DataSet {}: timestep \"{}\" is not a number", path.string(), out.size(), time));
      }
    }
    if (file.empty()) throw MeshError(fmt::format("{}: DataSet {} has no file", path.string(), out.size()));
    out.emplace_back(t, file);
  }
  if (out.empty()) throw MeshError(fmt::format("{}: lists no frames", path.string()));
  return out;
}

namespace {

using detail::Lexer;
using detail::xml_attribute;

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

/// The bytes of one value of VTK type `type`; 0 for an unknown type.
std::size_t vtk_type_size(std::string_view type) {
  if (type == "Float64" || type == "Int64" || type == "UInt64") return 8;
  if (type == "Float32" || type == "Int32" || type == "UInt32") return 4;
  if (type == "Int16" || type == "UInt16") return 2;
  if (type == "Int8" || type == "UInt8") return 1;
  return 0;
}

/// A .vtu file's text and what its header says, and the readers of its parts; every fault is a MeshError
/// naming the file and the line.
class VtuReader {
 public:
  explicit VtuReader(const std::filesystem::path& path)
      : path_(path),
        file_(path.string()),
        // A file that does not name VTKFile in its first 64 KiB fails before the rest is read. The XML is text
        // up to any appended data: the read stops at a NUL byte there (NUL padding).
        text_(detail::read_all(
            path,
            [&](const std::string& head) {
              if (head.find("<VTKFile") == std::string::npos)
                throw MeshError(fmt::format("{}:1: not a VTK UnstructuredGrid (.vtu) file", path.string()));
            },
            "<AppendedData")) {
    read_header();
  }

  [[noreturn]] void fail(std::size_t pos, const std::string& what) const {
    const auto line = 1 + static_cast<int>(std::count(text_.begin(), text_.begin() + std::min(pos, text_.size()), '\n'));
    throw MeshError(fmt::format("{}:{}: {}", file_, line, what));
  }

  /// The mesh's points and its tet and hex cells into the builder (other cells skipped, the indices of the
  /// kept ones in `kept`).
  void add_mesh(detail::MeshBuilder& b, Lexer& dummy, std::vector<long long>& kept) const {
    std::size_t where = 0;
    const std::vector<double> points = array("Points", nullptr, 3 * n_points_, where);
    for (long long i = 0; i < n_points_; ++i) b.vertex(dummy, i, points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    add_cells(b, dummy, kept);
  }

  /// Every named array of <PointData> and <CellData>, by its NumberOfComponents (1 if not given); a cell
  /// array keeps the values of the `kept` cells only.
  void data(const std::vector<long long>& kept, VtuData& out) const {
    for (const char* section : {"PointData", "CellData"}) {
      const std::size_t sec = text_.find(fmt::format("<{}", section), piece_);
      if (sec == std::string::npos) continue;
      const std::size_t sec_end = text_.find(fmt::format("</{}", section), sec);
      const bool cells = std::strcmp(section, "CellData") == 0;
      for (std::size_t at = text_.find("<DataArray", sec); at != std::string::npos && at < sec_end;
           at = text_.find("<DataArray", at + 1)) {
        const std::string_view tag = std::string_view(text_).substr(at, text_.find('>', at) - at);
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
        std::vector<double> values = array(section, name.c_str(), (cells ? n_cells_ : n_points_) * components, w);
        if (cells && static_cast<long long>(kept.size()) != n_cells_) {  // only the tet and hex cells' values
          std::vector<double> selected;
          for (long long c : kept)
            selected.insert(selected.end(), values.begin() + c * components, values.begin() + (c + 1) * components);
          values = std::move(selected);
        }
        (cells ? out.cell_data : out.point_data)[name] = std::move(values);
      }
    }
  }

  /// Only whitespace may follow the closing tag: a NUL-padded or damaged file is refused, not read in part.
  void check_end() const {
    const std::size_t close = text_.rfind("</VTKFile>");
    if (close == std::string::npos) fail(text_.size(), "no </VTKFile>: the file is cut short");
    if (const std::size_t after = text_.find_first_not_of(" \t\r\n", close + 10); after != std::string::npos)
      fail(after, "data after </VTKFile>");
  }

 private:
  /// The root's attributes (no compression, little-endian, the length headers' size), the appended data,
  /// and the piece's counts.
  void read_header() {
    const std::string& text = text_;
    if (const std::size_t nul = text.find('\0'); nul < text.find("<AppendedData")) {
      const std::size_t close = text.rfind("</VTKFile>", nul);
      fail(nul, close == std::string::npos ? "binary data (a NUL byte) where XML text was expected" : "data after </VTKFile>");
    }
    const std::size_t root = text.find("<VTKFile");
    if (root == std::string::npos || text.find("UnstructuredGrid") == std::string::npos)
      fail(0, "not a VTK UnstructuredGrid (.vtu) file");
    const std::string_view root_tag = std::string_view(text).substr(root, text.find('>', root) - root);
    if (const std::string c = xml_attribute(root_tag, "compressor"); !c.empty())
      fail(root, fmt::format("compressed data ({}) is not supported: write the file uncompressed", c));
    if (xml_attribute(root_tag, "byte_order") == "BigEndian") fail(root, "big-endian data is not supported");
    const std::string header_type = xml_attribute(root_tag, "header_type");
    header_size_ = header_type == "UInt64" ? 8 : 4;
    if (!header_type.empty() && header_type != "UInt32" && header_type != "UInt64")
      fail(root, fmt::format("unknown header_type \"{}\"", header_type));
    // The appended data: what follows the underscore, raw or base64.
    if (const std::size_t ad = text.find("<AppendedData"); ad != std::string::npos) {
      const std::string_view tag = std::string_view(text).substr(ad, text.find('>', ad) - ad);
      appended_base64_ = xml_attribute(tag, "encoding") == "base64";
      const std::size_t underscore = text.find('_', text.find('>', ad));
      if (underscore == std::string::npos) fail(ad, "<AppendedData> without the '_' that starts the data");
      appended_ = std::string_view(text).substr(underscore + 1);
    }
    piece_ = text.find("<Piece");
    if (piece_ == std::string::npos) fail(0, "no <Piece>");
    const std::string_view piece_tag = std::string_view(text).substr(piece_, text.find('>', piece_) - piece_);
    try {
      n_points_ = std::stoll(xml_attribute(piece_tag, "NumberOfPoints"));
      n_cells_ = std::stoll(xml_attribute(piece_tag, "NumberOfCells"));
    } catch (const std::exception&) {
      fail(piece_, "<Piece> needs NumberOfPoints and NumberOfCells");
    }
    if (n_points_ < 0 || n_cells_ < 0 || n_points_ > (1LL << 31) || n_cells_ > (1LL << 31))
      fail(piece_, "implausible point or cell count");
  }

  /// The bytes of a binary or appended DataArray (its length header first), at `at` with tag `tag`.
  std::string array_bytes(std::size_t at, std::string_view tag, const std::string& label, const std::string& format,
                          long long expected, std::size_t size) const {
    std::string bytes;
    if (format == "binary") {
      const std::size_t start = text_.find('>', at) + 1, end = text_.find("</DataArray>", start);
      if (end == std::string::npos) fail(at, "unterminated DataArray");
      if (!base64_decode(std::string_view(text_).substr(start, end - start), bytes)) fail(at, fmt::format("DataArray {}: invalid base64", label));
    } else if (format == "appended") {
      if (appended_.empty()) fail(at, fmt::format("DataArray {} is appended, but the file has no <AppendedData>", label));
      std::size_t offset = 0;
      try {
        offset = std::stoull(xml_attribute(tag, "offset"));
      } catch (const std::exception&) {
        fail(at, fmt::format("DataArray {} is appended but has no offset", label));
      }
      if (offset >= appended_.size()) fail(at, fmt::format("DataArray {}: offset {} is past the end of the appended data", label, offset));
      if (appended_base64_) {
        // Base64: the header, then the data, each its own stream; decode enough characters for both.
        const std::size_t chars = 4 * ((header_size_ + 2) / 3) + 4 * ((static_cast<std::size_t>(expected) * size + 2) / 3);
        if (!base64_decode(appended_.substr(offset, chars), bytes)) fail(at, fmt::format("DataArray {}: invalid base64", label));
      } else {
        bytes = std::string(appended_.substr(offset, header_size_ + static_cast<std::size_t>(expected) * size));
      }
    } else {
      fail(at, fmt::format("DataArray {} has unknown format \"{}\"", label, format));
    }
    return bytes;
  }

  /// The values of the DataArray named `name` inside `section` (or its first one), `expected` of them; `where`
  /// is set to the array's position (messages).
  std::vector<double> array(const char* section, const char* name, long long expected, std::size_t& where) const {
    const std::string& text = text_;
    const std::size_t sec = text.find(fmt::format("<{}", section), piece_);
    if (sec == std::string::npos) fail(piece_, fmt::format("no <{}> section", section));
    const std::size_t sec_end = text.find(fmt::format("</{}", section), sec);
    std::size_t at = sec;
    for (;;) {
      at = text.find("<DataArray", at + 1);
      if (at == std::string::npos || at > sec_end) fail(sec, fmt::format("no DataArray {} in <{}>", name ? name : "", section));
      const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
      if (!name || xml_attribute(tag, "Name") == name) break;
    }
    where = at;
    const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
    const std::string label = name ? name : section;
    const std::string format = xml_attribute(tag, "format"), type = xml_attribute(tag, "type");
    if (format == "ascii") {
      const std::size_t start = text.find('>', at) + 1, end = text.find("</DataArray>", start);
      if (end == std::string::npos) fail(at, "unterminated DataArray");
      std::vector<double> out;
      Lexer lx(path_, text.substr(start, end - start));
      const bool data_array = std::strcmp(section, "PointData") == 0 || std::strcmp(section, "CellData") == 0;
      while (!lx.at_end()) out.push_back(lx.number(label.c_str(), !data_array));
      if (static_cast<long long>(out.size()) != expected)
        fail(at, fmt::format("{} has {} values, expected {}", label, out.size(), expected));
      return out;
    }
    const std::size_t size = vtk_type_size(type);
    if (size == 0) fail(at, fmt::format("DataArray {} has unknown type \"{}\"", label, type));
    const std::string bytes = array_bytes(at, tag, label, format, expected, size);
    if (bytes.size() < header_size_) fail(at, fmt::format("DataArray {}: the data ends before its length header", label));
    std::uint64_t length = 0;
    std::memcpy(&length, bytes.data(), header_size_);  // little-endian: the low bytes come first
    if (length != static_cast<std::uint64_t>(expected) * size)
      fail(at, fmt::format("DataArray {}: its length header says {} bytes, expected {} ({} values of {})", label, length,
                           expected * size, expected, type));
    if (bytes.size() < header_size_ + length)
      fail(at, fmt::format("DataArray {}: the data ends after {} of its {} bytes", label, bytes.size() - header_size_, length));
    std::vector<double> out = *decode_values(type, bytes.data() + header_size_, static_cast<std::size_t>(expected));
    if (std::strcmp(section, "Points") == 0)
      for (double v : out)
        if (!std::isfinite(v)) fail(at, "a point coordinate is not finite");
    return out;
  }

  /// The tet and hex cells into the builder (surface, line and vertex cells skipped), their indices in `kept`.
  void add_cells(detail::MeshBuilder& b, Lexer& dummy, std::vector<long long>& kept) const {
    std::size_t w_off = 0, w_types = 0, w_conn = 0;
    const std::vector<double> offsets = array("Cells", "offsets", n_cells_, w_off);
    const std::vector<double> types = array("Cells", "types", n_cells_, w_types);
    // Offsets, types and connectivity arrive as doubles: each must be a whole number a double holds exactly
    // (|v| <= 2^53), never cast blindly (a cast of 2.4e28 to an integer is undefined).
    auto whole = [&](double v, std::size_t at, const char* what) {
      if (!(std::abs(v) <= 9007199254740992.0) || v != std::floor(v))
        fail(at, fmt::format("{}: {:g} is not an index (a whole number no larger than 2^53)", what, v));
      return static_cast<long long>(v);
    };
    long long total = n_cells_ ? whole(offsets.back(), w_off, "offsets") : 0;
    if (total < 0 || total > (1LL << 33)) fail(w_off, "implausible offsets");
    const std::vector<double> conn = array("Cells", "connectivity", total, w_conn);
    long long previous = 0;
    for (long long c = 0; c < n_cells_; ++c) {
      const long long type = whole(types[c], w_types, "types"), end = whole(offsets[c], w_off, "offsets");
      if (end < previous || end > total) fail(w_off, fmt::format("cell {}: offsets are not increasing", c));
      if (type == 5 || type == 9 || type == 3 || type == 1) {  // surface / line / vertex cells: skipped
        previous = end;
        continue;
      }
      kept.push_back(c);
      const int nodes = type == 10 ? 4 : type == 12 ? 8 : -1;
      if (nodes < 0) fail(w_types, fmt::format("cell {} has unsupported VTK type {} (tets 10 and hexes 12 only)", c, type));
      if (end - previous != nodes) fail(w_off, fmt::format("cell {}: offsets give {} nodes for a {}-node cell", c, end - previous, nodes));
      std::vector<long long> ids(nodes);
      for (int a = 0; a < nodes; ++a) ids[a] = whole(conn[previous + a], w_conn, "connectivity");
      for (long long id : ids)
        if (id < 0 || id >= n_points_) fail(w_conn, fmt::format("cell {} refers to point {}, which does not exist", c, id));
      b.cell(dummy, nodes == 4 ? CellType::tet4 : CellType::hex8, nodes == 4 ? ids : detail::hex_to_lattice(ids), 0);
      previous = end;
    }
  }

  std::filesystem::path path_;
  std::string file_;
  std::string text_;
  std::size_t header_size_ = 4;      ///< bytes of a binary array's length header (UInt32 or UInt64)
  std::string_view appended_;        ///< the appended data after its '_'
  bool appended_base64_ = false;
  std::size_t piece_ = 0;            ///< where <Piece> starts
  long long n_points_ = -1, n_cells_ = -1;
};

/// Reads a .vtu file's mesh; when `data` is given, also every named array of <PointData> and <CellData>.
MeshFile read_vtu_file(const std::filesystem::path& path, VtuData* data) {
  const VtuReader reader(path);
  detail::MeshBuilder b;
  Lexer dummy(path, "");        // the builder reports through a lexer; .vtu cells have no line of their own
  std::vector<long long> kept;  // the tet and hex cells, by index in the file
  reader.add_mesh(b, dummy, kept);
  if (data) reader.data(kept, *data);
  reader.check_end();
  return b.finish(dummy);
}

}  // namespace

MeshFile read_vtu(const std::filesystem::path& path) { return read_vtu_file(path, nullptr); }

VtuData read_vtu_data(const std::filesystem::path& path) {
  VtuData out;
  out.mesh = read_vtu_file(path, &out);
  return out;
}

}  // namespace snh
