// Mesh readers: TetGen, MEDIT, Gmsh 2.2 / 4.1 and VTU read the same small meshes; the checks re-orient
// inverted cells and give one-line errors naming the file and line for malformed input.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <cstdint>
#include <fstream>

#include <fmt/format.h>

#include "snh/io/mesh_read.hpp"
#include "snh/io/mesh_write.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/box.hpp"
#include "io/bytes_read.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

class MeshRead : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snh_test_mesh_read_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return dir_ / name;
  }
  /// The error message of reading `name` with `text`, or "" if it reads.
  std::string error_of(const std::string& name, const std::string& text) {
    const fs::path p = write(name, text);
    try {
      (void)read_mesh(p);
    } catch (const MeshError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
      return msg.substr(p.string().size());  // drop the directory for comparison
    }
    return "";
  }
  /// The error message of reading what is already at `name`, or "" if it reads.
  std::string error_of_existing(const std::string& name) {
    const fs::path p = dir_ / name;
    try {
      (void)read_mesh(p);
    } catch (const MeshError& e) {
      return std::string(e.what()).substr(p.string().size());
    }
    return "";
  }
  fs::path dir_;
};

// Two tets sharing a face, the second given inverted in the file.
const char* kNode = "# two tets\n5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
const char* kEle = "2 4 0\n1 1 2 3 4\n2 2 4 3 5\n";

TEST_F(MeshRead, TetGenPairReadsFromEitherFileAndReorients) {
  write("t.node", kNode);
  const fs::path ele = write("t.ele", kEle);
  for (const fs::path& p : {ele, dir_ / "t.node"}) {
    const MeshFile m = read_mesh(p);
    EXPECT_EQ(m.mesh.type, CellType::tet4);
    EXPECT_EQ(m.mesh.vertex_count(), 5);
    ASSERT_EQ(m.mesh.cell_count(), 2);
    EXPECT_EQ(m.mesh.cells(0, 0), 0);
    EXPECT_EQ(m.reoriented, 1) << "the second tet is inverted in the file";
    EXPECT_EQ(m.cell_lines[1], 3);
  }
}

TEST_F(MeshRead, AllFormatsAgreeOnATwoHexMesh) {
  // Two unit cubes along x: vertices in lattice order (i + 3 j + 6 k), hexes in VTK order in the files.
  const VolumeMesh ref = [] {
    VolumeMesh m = box_hexes(1);
    m.vertices.resize(3, 12);
    m.cells.resize(8, 2);
    for (int k = 0; k < 2; ++k)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 3; ++i) m.vertices.col(i + 3 * j + 6 * k) = Eigen::Vector3d(i, j, k);
    for (int c = 0; c < 2; ++c)
      for (int a = 0; a < 8; ++a) m.cells(a, c) = c + (a & 1) + 3 * ((a >> 1) & 1) + 6 * (a >> 2);
    return m;
  }();
  auto vtk_order = [&](int c, int base) {  // one hex's nodes in VTK order, 0- or 1-based
    std::string s;
    for (int a : {0, 1, 3, 2, 4, 5, 7, 6}) s += " " + std::to_string(ref.cells(a, c) + base);
    return s;
  };
  std::string coords0, coords1;
  for (int v = 0; v < 12; ++v) {
    const auto x = ref.vertices.col(v);
    coords0 += fmt::format("{} {} {} {}\n", v + 1, x[0], x[1], x[2]);
    coords1 += fmt::format("{} {} {} 0\n", x[0], x[1], x[2]);
  }
  const std::string medit = "MeshVersionFormatted 2\nDimension 3\nVertices 12\n" + coords1 +
                            "Quadrilaterals 1\n1 2 5 4 0\nHexahedra 2\n" + vtk_order(0, 1) + " 0\n" + vtk_order(1, 1) +
                            " 0\nEnd\n";
  const std::string gmsh2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"body\"\n$EndPhysicalNames\n$Nodes\n12\n" +
                            coords0 + "$EndNodes\n$Elements\n3\n1 15 2 0 1 1\n2 5 2 1 1" + vtk_order(0, 1) + "\n3 5 2 1 1" +
                            vtk_order(1, 1) + "\n$EndElements\n";
  std::string gmsh4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 12 1 12\n3 1 0 12\n";
  for (int v = 1; v <= 12; ++v) gmsh4 += std::to_string(v) + "\n";
  for (int v = 0; v < 12; ++v) gmsh4 += fmt::format("{} {} {}\n", ref.vertices(0, v), ref.vertices(1, v), ref.vertices(2, v));
  gmsh4 += "$EndNodes\n$Elements\n1 2 1 2\n3 1 5 2\n1" + vtk_order(0, 1) + "\n2" + vtk_order(1, 1) + "\n$EndElements\n";
  const fs::path vtu = dir_ / "h.vtu";
  write_vtu(vtu, ref, ref.vertices, {}, {});
  for (const fs::path& p : {write("h.mesh", medit), write("h2.msh", gmsh2), write("h4.msh", gmsh4), vtu}) {
    const MeshFile m = read_mesh(p);
    EXPECT_EQ(m.mesh.type, CellType::hex8) << p;
    EXPECT_EQ(m.mesh.vertices, ref.vertices) << p;
    EXPECT_EQ(m.mesh.cells, ref.cells) << p;
    EXPECT_EQ(m.reoriented, 0) << p;
  }
}

TEST_F(MeshRead, CellTagsAreEachFormatsRegions) {
  // Two unit cubes along x (12 vertices, i + 3 j + 6 k), each hex in VTK order, 1-based.
  std::string coords0, coords1;
  for (int v = 0; v < 12; ++v) {
    coords0 += fmt::format("{} {} {} {}\n", v + 1, v % 3, (v / 3) % 2, v / 6);
    coords1 += fmt::format("{} {} {} 0\n", v % 3, (v / 3) % 2, v / 6);
  }
  const auto hex = [](int c) {
    std::string s;
    for (int a : {0, 1, 3, 2, 4, 5, 7, 6}) s += " " + std::to_string(c + (a & 1) + 3 * ((a >> 1) & 1) + 6 * (a >> 2) + 1);
    return s;
  };
  const std::string medit = "MeshVersionFormatted 2\nDimension 3\nVertices 12\n" + coords1 + "Hexahedra 2\n" + hex(0) + " 7\n" + hex(1) +
                            " 9\nEnd\n";
  const std::string gmsh2 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n12\n" + coords0 + "$EndNodes\n$Elements\n2\n1 5 2 3 11" + hex(0) +
                            "\n2 5 2 4 12" + hex(1) + "\n$EndElements\n";
  std::string gmsh4 = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 12 1 12\n3 1 0 12\n";
  for (int v = 1; v <= 12; ++v) gmsh4 += std::to_string(v) + "\n";
  for (int v = 0; v < 12; ++v) gmsh4 += fmt::format("{} {} {}\n", v % 3, (v / 3) % 2, v / 6);
  gmsh4 += "$EndNodes\n$Elements\n2 2 1 2\n3 5 5 1\n1" + hex(0) + "\n3 6 5 1\n2" + hex(1) + "\n$EndElements\n";
  const std::vector<std::pair<fs::path, std::vector<long long>>> cases = {
      {write("t.mesh", medit), {7, 9}}, {write("t2.msh", gmsh2), {3, 4}}, {write("t4.msh", gmsh4), {5, 6}}};
  for (const auto& [p, tags] : cases) EXPECT_EQ(read_mesh(p).cell_tags, tags) << p;
  // TetGen's region attributes (a whole number each; another is no tag); without the flag, all 0.
  write("r.node", kNode);
  EXPECT_EQ(read_mesh(write("r.ele", "2 4 1\n1 1 2 3 4 10\n2 2 4 3 5 2.5\n")).cell_tags, (std::vector<long long>{10, 0}));
  write("n.node", kNode);
  EXPECT_EQ(read_mesh(write("n.ele", kEle)).cell_tags, (std::vector<long long>{0, 0}));
}

/// Appends the bytes of a value.
template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

TEST_F(MeshRead, BinaryGmsh22And41) {
  // One unit cube (8 nodes) as a hex, node tags 11..18, a binary $Entities section to skip.
  const int lattice[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};  // VTK order
  std::string v41 = "$MeshFormat\n4.1 1 8\n";
  put<std::int32_t>(v41, 1);
  v41 += "\n$EndMeshFormat\n$Entities\n";
  v41 += std::string("\x01\x00\n$End\x07\xff", 8);  // arbitrary bytes
  v41 += "\n$EndEntities\n$Nodes\n";
  for (std::uint64_t v : {1, 8, 11, 18}) put<std::uint64_t>(v41, v);
  put<std::int32_t>(v41, 3); put<std::int32_t>(v41, 1); put<std::int32_t>(v41, 0); put<std::uint64_t>(v41, 8);
  for (int i = 0; i < 8; ++i) put<std::uint64_t>(v41, 11 + i);
  for (const auto& p : lattice)
    for (int a = 0; a < 3; ++a) put<double>(v41, p[a]);
  v41 += "\n$EndNodes\n$Elements\n";
  for (std::uint64_t v : {1, 1, 1, 1}) put<std::uint64_t>(v41, v);
  put<std::int32_t>(v41, 3); put<std::int32_t>(v41, 1); put<std::int32_t>(v41, 5); put<std::uint64_t>(v41, 1);
  put<std::uint64_t>(v41, 1);
  for (int i = 0; i < 8; ++i) put<std::uint64_t>(v41, 11 + i);
  v41 += "\n$EndElements\n";

  std::string v22 = "$MeshFormat\n2.2 1 8\n";
  put<std::int32_t>(v22, 1);
  v22 += "\n$EndMeshFormat\n$Nodes\n8\n";
  for (int i = 0; i < 8; ++i) {
    put<std::int32_t>(v22, 11 + i);
    for (int a = 0; a < 3; ++a) put<double>(v22, lattice[i][a]);
  }
  v22 += "\n$EndNodes\n$Elements\n1\n";
  put<std::int32_t>(v22, 5); put<std::int32_t>(v22, 1); put<std::int32_t>(v22, 2);
  put<std::int32_t>(v22, 1); put<std::int32_t>(v22, 7); put<std::int32_t>(v22, 7);
  for (int i = 0; i < 8; ++i) put<std::int32_t>(v22, 11 + i);
  v22 += "\n$EndElements\n";

  for (const auto& [name, bytes] : {std::pair{"b41.msh", v41}, {"b22.msh", v22}}) {
    const MeshFile m = read_mesh(write(name, bytes));
    EXPECT_EQ(m.mesh.type, CellType::hex8) << name;
    ASSERT_EQ(m.mesh.cell_count(), 1) << name;
    for (int a = 0; a < 8; ++a)  // lattice order: corner a at (a & 1, a >> 1 & 1, a >> 2)
      EXPECT_EQ(m.mesh.vertices.col(m.mesh.cells(a, 0)), Eigen::Vector3d(a & 1, (a >> 1) & 1, a >> 2)) << name << " corner " << a;
  }
  // Truncated binary data: a one-line error.
  EXPECT_NE(error_of("t41.msh", v41.substr(0, v41.size() - 40)).find("the file ends inside binary data"), std::string::npos);
}

std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 2]);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? k[v & 63] : '=';
  }
  return out;
}

TEST_F(MeshRead, BinaryAndAppendedVtu) {
  // One hex: points Float32, connectivity Int64, offsets Int32, types UInt8; UInt32 and UInt64 headers.
  const int lattice[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  std::string points, conn, offsets, types;
  for (const auto& p : lattice)
    for (int a = 0; a < 3; ++a) put<float>(points, static_cast<float>(p[a]));
  for (int i = 0; i < 8; ++i) put<std::int64_t>(conn, i);
  put<std::int32_t>(offsets, 8);
  put<std::uint8_t>(types, 12);
  for (const std::string header : {"UInt32", "UInt64"}) {
    auto with_length = [&](const std::string& data) {
      std::string h;
      if (header == "UInt32") put<std::uint32_t>(h, static_cast<std::uint32_t>(data.size()));
      else put<std::uint64_t>(h, data.size());
      return std::pair{h, data};
    };
    const std::string head = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"" +
                             header + "\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n";
    const std::pair<const char*, std::string> arrays[4] = {
        {"<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\"", points},
        {"</Points><Cells><DataArray type=\"Int64\" Name=\"connectivity\"", conn},
        {"<DataArray type=\"Int32\" Name=\"offsets\"", offsets},
        {"<DataArray type=\"UInt8\" Name=\"types\"", types}};
    // Inline base64, header and data encoded separately.
    std::string inline_file = head;
    for (const auto& [tag, data] : arrays) {
      const auto [h, d] = with_length(data);
      inline_file += std::string(tag) + " format=\"binary\">" + base64(h) + base64(d) + "</DataArray>\n";
    }
    inline_file += "</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    // Appended, raw and base64.
    std::string files[2];
    for (int enc = 0; enc < 2; ++enc) {
      std::string f = head, blob;
      for (const auto& [tag, data] : arrays) {
        f += std::string(tag) + " format=\"appended\" offset=\"" + std::to_string(blob.size()) + "\"/>\n";
        const auto [h, d] = with_length(data);
        blob += enc == 0 ? h + d : base64(h) + base64(d);
      }
      f += "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"" + std::string(enc == 0 ? "raw" : "base64") +
           "\">\n_" + blob + "\n</AppendedData>\n</VTKFile>\n";
      files[enc] = f;
    }
    for (const auto& [name, content] : {std::pair{"inline.vtu", inline_file}, {"raw.vtu", files[0]}, {"b64.vtu", files[1]}}) {
      const MeshFile m = read_mesh(write(header + name, content));
      ASSERT_EQ(m.mesh.cell_count(), 1) << header << name;
      for (int a = 0; a < 8; ++a)
        EXPECT_EQ(m.mesh.vertices.col(m.mesh.cells(a, 0)), Eigen::Vector3d(a & 1, (a >> 1) & 1, a >> 2)) << header << name;
    }
  }
}

TEST_F(MeshRead, OurOwnTetFramesReadBack) {
  const VolumeMesh t = box_tets(2);
  write_vtu(dir_ / "t.vtu", t, t.vertices, {{"displacement", Eigen::Matrix3Xd::Zero(3, t.vertex_count())}},
            {{"J", Eigen::VectorXd::Ones(t.cell_count())}});
  const MeshFile m = read_mesh(dir_ / "t.vtu");
  EXPECT_TRUE(m.mesh.vertices.isApprox(t.vertices));
  EXPECT_EQ(m.mesh.cells, t.cells);
}

TEST_F(MeshRead, MalformedFilesGiveOneLineErrors) {
  write("a.node", kNode);
  EXPECT_EQ(error_of("a.ele", "2 4 0\n1 1 2 3 4\n"), ":3: the file ends where a tetrahedron index was expected");
  EXPECT_EQ(error_of("b.node", "2 3 0 0\n1 0 0 0\n2 0 nan 0\n"), ":3: y is not finite: 'nan'");
  write("c.node", kNode);
  EXPECT_EQ(error_of("c.ele", "1 4 0\n1 1 2 3 9\n"), ":2: cell refers to vertex 9, which does not exist");
  write("d.node", kNode);
  EXPECT_EQ(error_of("d.ele", "2 4 0\n1 1 2 3 3\n2 2 3 4 5\n"), ":2: cell 0: vertex 2 appears twice");
  write("e.node", kNode);
  EXPECT_EQ(error_of("e.ele", "1 4 0\n1 1 2 3 4\n"), ": vertex 4 is not used by any cell");
  write("f.node", "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 1 1 0\n");
  EXPECT_NE(error_of("f.ele", "1 4 0\n1 1 2 3 4\n").find(":2: cell 0: degenerate (rest volume 0"), std::string::npos);
  write("g.node", kNode);
  EXPECT_EQ(error_of("g.ele", "1 10 0\n"), ":1: only linear tetrahedra (4 nodes) are supported, got 10 nodes");
  write("h.node", kNode);
  EXPECT_EQ(error_of("h.ele", "1 4 0\n1 1 2 3 4\n2 2 3 4 5\n"), ":3: more data than the 1 tetrahedra the header announces");
  EXPECT_EQ(error_of("i.msh", "$MeshFormat\n4.1 1 8\n"), ":2: the file ends inside binary data (reading the endianness check)");
  EXPECT_EQ(error_of("j.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n1\n1 6 0 1 1 1 1 1 1\n"),
            ":10: prism cells are not supported (tets or hexes only)");
  EXPECT_EQ(error_of("k.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n$EndNodes\n"),
            ":7: expected a node tag (an integer), got '$EndNodes'");
  EXPECT_EQ(error_of("l.mesh", "MeshVersionFormatted 2\nDimension 3\nPrisms 1\n"), ":3: unknown or unsupported section 'Prisms'");
  EXPECT_EQ(error_of("m.xyz", "1 2 3\n"),
            ": unknown mesh format '.xyz' (known: .node/.ele, .mesh, .msh, .vtu; surfaces .obj, .off, .ply, .stl)");
  EXPECT_EQ(error_of("n.vtu", "<VTKFile type=\"UnstructuredGrid\">\n<AppendedData encoding=\"raw\">"),
            ":2: <AppendedData> without the '_' that starts the data");
  EXPECT_EQ(error_of("o.vtu", "<VTKFile type=\"UnstructuredGrid\" compressor=\"vtkZLibDataCompressor\">"),
            ":1: compressed data (vtkZLibDataCompressor) is not supported: write the file uncompressed");
  EXPECT_THROW((void)read_mesh(dir_ / "missing.mesh"), MeshError);
}

TEST_F(MeshRead, AWrongLengthHeaderIsNamed) {
  // The Points of one hex (24 Float32 values, 96 bytes) appended raw under a length header of 1000.
  std::string blob;
  put<std::uint32_t>(blob, 1000);
  for (int i = 0; i < 24; ++i) put<float>(blob, 0.0F);
  const std::string f =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
      "<UnstructuredGrid>\n<Piece NumberOfPoints=\"8\" NumberOfCells=\"1\">\n<Points><DataArray type=\"Float32\" "
      "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>\n</Points>\n</Piece>\n</UnstructuredGrid>\n"
      "<AppendedData encoding=\"raw\">\n_" + blob + "\n</AppendedData>\n</VTKFile>\n";
  EXPECT_EQ(error_of("len.vtu", f), ":5: DataArray Points: its length header says 1000 bytes, expected 96 (24 values of Float32)");
}

// Every reader opens its file through one check (io/input_file): a directory, a FIFO or a device fails at
// once, a file of something else fails on its first line without being read whole, and anything but
// whitespace after the end of a mesh is refused.
TEST_F(MeshRead, InputFilesAreCheckedBeforeReading) {
  fs::create_directories(dir_ / "d.msh");
  EXPECT_EQ(error_of_existing("d.msh"), ": is a directory, not a mesh file");
  ASSERT_EQ(::mkfifo((dir_ / "f.mesh").c_str(), 0644), 0);
  EXPECT_EQ(error_of_existing("f.mesh"), ": is not a regular file (a FIFO): cannot read a mesh file from it");
  fs::create_symlink("/dev/zero", dir_ / "z.vtu");
  EXPECT_EQ(error_of_existing("z.vtu"), ": is not a regular file (a character device): cannot read a mesh file from it");
  // 10 MB of zeros, and of one long word: the first 64 KiB decide; the five files (50 MB) are not read whole.
  const long long before = test::bytes_read();
  EXPECT_EQ(error_of("zeros.msh", std::string(10 << 20, '\0')), ":1: binary data (a NUL byte) where text was expected");
  EXPECT_EQ(error_of("zeros.mesh", std::string(10 << 20, '\0')), ":1: binary data (a NUL byte) where text was expected");
  EXPECT_EQ(error_of("zeros.node", std::string(10 << 20, '\0')), ":1: binary data (a NUL byte) where text was expected");
  EXPECT_EQ(error_of("zeros.vtu", std::string(10 << 20, '\0')), ":1: not a VTK UnstructuredGrid (.vtu) file");
  EXPECT_EQ(error_of("a.msh", std::string(10 << 20, 'a')), ":1: a word longer than 4096 characters where text was expected");
  if (before >= 0) {
    EXPECT_LT(test::bytes_read() - before, 2 << 20);  // bytes, not seconds: a busy machine cannot fail it
  }
}

TEST_F(MeshRead, DataAfterTheMeshIsRefused) {
  const VolumeMesh t = box_tets(1);
  write_msh(dir_ / "ok.msh", t);
  write_medit(dir_ / "ok.mesh", t);
  write_vtu(dir_ / "ok.vtu", t, t.vertices, {}, {});
  for (const char* name : {"ok.msh", "ok.mesh", "ok.vtu"}) {
    std::ifstream in(dir_ / name, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(error_of(name, text), "") << name;
    const std::string ext = fs::path(name).extension().string();
    const std::string padded = error_of("padded" + ext, text + std::string(1 << 20, '\0'));
    EXPECT_TRUE(padded.find("binary data (a NUL byte) where text was expected") != std::string::npos ||
                padded.find("data after </VTKFile>") != std::string::npos)
        << name << ": " << padded;
    EXPECT_NE(error_of("words" + ext, text + "\nmore words\n"), "") << name;
  }
  write("p.node", kNode);
  EXPECT_NE(error_of("p.ele", std::string(kEle) + std::string(100, '\0')).find(":4: more data than the 2 tetrahedra the header announces"), std::string::npos);
  EXPECT_EQ(error_of("q.mesh", "MeshVersionFormatted 2\nDimension 3\nEnd\ngarbage\n"), ":4: unexpected 'garbage' after End");
}

// A valid mesh followed by 900 MB of NUL bytes (a sparse file: no disk used) fails after reading about as
// much as the mesh, not the whole file: the text readers read as they parse, and an ASCII VTU's XML stops
// at its first NUL byte (before: the whole file in memory, 4.45 s, before the error). (A VTU with appended
// binary data, as snh writes its frames, is still read whole, up to the 1 GiB limit, before it fails.)
TEST_F(MeshRead, APaddedFileIsReadOnlyUpToItsPadding) {
  if (test::bytes_read() < 0) GTEST_SKIP() << "no /proc/self/io";
  const VolumeMesh t = box_tets(2);
  write_msh(dir_ / "p.msh", t);
  write_medit(dir_ / "p.mesh", t);
  write("p.vtu",
        "<VTKFile type=\"UnstructuredGrid\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"4\" NumberOfCells=\"1\">\n"
        "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0 0 0 1</DataArray></Points>\n"
        "<Cells><DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">0 1 2 3</DataArray>\n"
        "<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">4</DataArray>\n"
        "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">10</DataArray></Cells>\n"
        "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
  EXPECT_EQ(error_of_existing("p.vtu"), "");
  write("p.node", kNode);
  write("p.ele", kEle);
  constexpr std::uintmax_t padded_size = 900u << 20;
  for (const char* name : {"p.msh", "p.mesh", "p.vtu", "p.ele"}) {
    fs::resize_file(dir_ / name, padded_size);
    const long long before = test::bytes_read();
    const std::string error = error_of_existing(name);
    const long long read = test::bytes_read() - before;
    EXPECT_TRUE(error.find("binary data (a NUL byte) where text was expected") != std::string::npos ||
                error.find("data after </VTKFile>") != std::string::npos ||
                error.find("more data than the 2 tetrahedra the header announces") != std::string::npos)
        << name << ": " << error;
    EXPECT_LT(read, 8 << 20) << name << ": read " << read << " bytes of " << padded_size;
  }
  // The same for a NUL in the middle of a text mesh: the read stops there, at its line.
  const std::string text = "MeshVersionFormatted 2\nDimension 3\nVertices\n4\n0 0 0 0\n";
  EXPECT_EQ(error_of("mid.mesh", text + std::string(1, '\0') + std::string(3 << 20, ' ')),
            ":6: binary data (a NUL byte) where text was expected");
  EXPECT_EQ(error_of("c.mesh", std::string("# a comment with a NUL \0 byte\nMeshVersionFormatted 2\n", 53)),
            ":1: binary data (a NUL byte) where text was expected");
}

}  // namespace
}  // namespace snh
