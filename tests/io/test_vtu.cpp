// VTU frames: the binary layout (appended raw data) decoded by the format's rules, counts, VTK's
// hexahedron corner order (positive volume in VTK's convention), the data arrays read back bit for bit,
// the .pvd series; and atomic writes leave no temporary files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "snh/io/atomic_file.hpp"
#include "snh/io/obj.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

using test::file_text;

/// The value of attribute `name` in `tag`, "" if it has none.
std::string attribute(const std::string& tag, const std::string& name) {
  const auto at = tag.find(" " + name + "=\"");
  if (at == std::string::npos) return "";
  const auto start = at + name.size() + 3;
  return tag.substr(start, tag.find('"', start) - start);
}

/// A .vtu frame decoded by the VTK XML format's rules, independently of read_vtu: the XML, then
/// <AppendedData encoding="raw">, '_', and each array at its offset as a UInt64 byte count and its values.
/// Checks the layout as it goes (EXPECT): every array appended, the arrays back to back from offset 0 in
/// the order of their tags, the byte counts those of NumberOfPoints / NumberOfCells values, and the file
/// ending right after the last array.
struct Decoded {
  std::string xml;                                     // the text before <AppendedData>
  std::map<std::string, std::vector<double>> arrays;   // by Name (the points: "Points"), as doubles
  std::map<std::string, std::string> types;            // VTK type by Name
};
Decoded decode(const fs::path& path) {
  Decoded d;
  const std::string file = file_text(path);
  const auto ad = file.find("<AppendedData encoding=\"raw\">\n_");
  if (ad == std::string::npos) {
    ADD_FAILURE() << "no raw appended data";
    return d;
  }
  d.xml = file.substr(0, ad);
  const std::size_t data = ad + std::string("<AppendedData encoding=\"raw\">\n_").size();
  const std::string root = d.xml.substr(d.xml.find("<VTKFile"), d.xml.find('>', d.xml.find("<VTKFile")) - d.xml.find("<VTKFile"));
  EXPECT_EQ(attribute(root, "type"), "UnstructuredGrid");
  EXPECT_EQ(attribute(root, "byte_order"), "LittleEndian");
  EXPECT_EQ(attribute(root, "header_type"), "UInt64");
  EXPECT_EQ(attribute(root, "version"), "1.0");  // VTK reads UInt64 headers from version 1.0 on
  const std::string piece = d.xml.substr(d.xml.find("<Piece"), d.xml.find('>', d.xml.find("<Piece")) - d.xml.find("<Piece"));
  const std::size_t points = std::stoul(attribute(piece, "NumberOfPoints")), cells = std::stoul(attribute(piece, "NumberOfCells"));
  std::uint64_t expected_offset = 0;
  for (auto at = d.xml.find("<DataArray"); at != std::string::npos; at = d.xml.find("<DataArray", at + 1)) {
    const std::string tag = d.xml.substr(at, d.xml.find('>', at) - at);
    const std::string name = attribute(tag, "Name").empty() ? "Points" : attribute(tag, "Name");
    EXPECT_EQ(attribute(tag, "format"), "appended") << name;
    EXPECT_EQ(tag.back(), '/') << name << ": an appended DataArray is an empty element";
    const std::uint64_t offset = std::stoull(attribute(tag, "offset"));
    EXPECT_EQ(offset, expected_offset) << name;
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, file.data() + data + offset, 8);
    const std::string type = attribute(tag, "type");
    const std::size_t size = type == "UInt8" ? 1 : 8;
    const std::size_t components = attribute(tag, "NumberOfComponents").empty() ? 1 : std::stoul(attribute(tag, "NumberOfComponents"));
    const bool in_cells = d.xml.rfind("<CellData>", at) != std::string::npos;
    if (name != "connectivity") {
      EXPECT_EQ(bytes, size * components * (name == "offsets" || name == "types" || in_cells ? cells : points)) << name;
    }
    std::vector<double>& values = d.arrays[name];
    for (std::uint64_t i = 0; i < bytes / size; ++i) {
      const char* p = file.data() + data + offset + 8 + i * size;
      double f = 0.0;
      std::int64_t i64 = 0;
      if (type == "Float64") values.push_back((std::memcpy(&f, p, 8), f));
      else if (type == "Int64") values.push_back(static_cast<double>((std::memcpy(&i64, p, 8), i64)));
      else if (type == "UInt8") values.push_back(static_cast<unsigned char>(*p));
      else ADD_FAILURE() << name << ": unexpected type " << type;
    }
    d.types[name] = type;
    expected_offset = offset + 8 + bytes;
  }
  EXPECT_EQ(file.substr(data + expected_offset), "\n</AppendedData>\n</VTKFile>\n");
  return d;
}

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("snh_io_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(Vtu, HexFrameUsesVtkOrderAndCarriesData) {
  const fs::path dir = temp_dir("vtu");
  const VolumeMesh m = box_hexes(2);
  const Eigen::Matrix3Xd X = m.vertices * 1.5;
  Eigen::VectorXd J = Eigen::VectorXd::Constant(m.cell_count(), 3.375);
  write_vtu(dir / "f.vtu", m, X, {{"displacement", X - m.vertices}}, {{"J", J}});
  const Decoded d = decode(dir / "f.vtu");
  EXPECT_NE(d.xml.find("NumberOfPoints=\"27\" NumberOfCells=\"8\""), std::string::npos);
  const auto& pts = d.arrays.at("Points");
  ASSERT_EQ(pts.size(), 81u);
  const auto& conn = d.arrays.at("connectivity");
  ASSERT_EQ(conn.size(), 64u);
  EXPECT_EQ(d.types.at("connectivity"), "Int64");
  EXPECT_EQ(d.arrays.at("offsets").back(), 64);
  EXPECT_EQ(d.types.at("types"), "UInt8");
  for (double t : d.arrays.at("types")) EXPECT_EQ(t, 12);  // VTK_HEXAHEDRON
  for (int c = 0; c < 8; ++c) {
    EXPECT_EQ(d.arrays.at("offsets")[c], 8 * (c + 1));
    auto p = [&](int a) {
      const int v = static_cast<int>(conn[8 * c + a]);
      return Eigen::Vector3d(pts[3 * v], pts[3 * v + 1], pts[3 * v + 2]);
    };
    // VTK: points 0-3 go around the bottom face, 4-7 above them: (p1−p0)×(p3−p0) points to p4.
    EXPECT_GT((p(1) - p(0)).cross(p(3) - p(0)).dot(p(4) - p(0)), 0.0) << "cell " << c;
    EXPECT_NEAR((p(2) - p(0)).norm(), std::sqrt(2.0) * 1.5, 1e-12);  // p2 is diagonal from p0
  }
  EXPECT_EQ(d.arrays.at("J"), std::vector<double>(8, 3.375));
  EXPECT_EQ(d.arrays.at("displacement").size(), 81u);
  EXPECT_EQ(d.arrays.at("displacement")[3 * 26], 0.5);  // the corner (1, 1, 1) moved to 1.5
  write_pvd(dir / "s.pvd", {{0.0, "f.vtu"}, {1.0, "g.vtu"}});
  const std::string pvd = file_text(dir / "s.pvd");
  EXPECT_NE(pvd.find("<DataSet timestep=\"1\" group=\"\" part=\"0\" file=\"g.vtu\"/>"), std::string::npos);
  // Nothing but the two files: the temporaries were renamed.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  fs::remove_all(dir);
}

TEST(Vtu, TetFrameTypes) {
  const fs::path dir = temp_dir("vtu_tet");
  const VolumeMesh m = box_tets(1);
  write_vtu(dir / "t.vtu", m, m.vertices, {}, {});
  const Decoded d = decode(dir / "t.vtu");
  const auto& types = d.arrays.at("types");
  ASSERT_EQ(types.size(), 6u);
  for (double t : types) EXPECT_EQ(t, 10);  // VTK_TETRA
  EXPECT_EQ(d.arrays.at("connectivity").size(), 24u);
  fs::remove_all(dir);
}

// Every value comes back bit for bit through read_vtu_data: awkward doubles in the points and fields,
// non-finite ones in a cell field. One writer writes two frames (its cell arrays are made once) and a
// frame it writes is byte for byte write_vtu's.
TEST(Vtu, FramesReadBackBitForBit) {
  const fs::path dir = temp_dir("vtu_bits");
  const VolumeMesh m = box_hexes(2);
  Eigen::Matrix3Xd X = m.vertices + 0.01 * m.vertices.array().sin().matrix();
  X(0, 1) = 1.0 / 3.0;
  X(1, 2) = -0.0;
  X(2, 3) = 4.9e-324;  // the smallest subnormal
  X(0, 4) = 1e300;
  const double special[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(), -0.0, 2.2250738585072014e-308, 0.1, -1e-17, 123456789.123456789};
  Eigen::VectorXd psi = Eigen::Map<const Eigen::VectorXd>(special, 8), pinned = Eigen::VectorXd::Zero(m.vertex_count());
  pinned[5] = 1.0;
  const VtuWriter writer(m);
  for (int frame = 0; frame < 2; ++frame) {
    const Eigen::Matrix3Xd Y = X * (1.0 + frame / 7.0);
    const fs::path path = dir / ("f" + std::to_string(frame) + ".vtu");
    writer.write(path, Y, {{"displacement", Y - m.vertices}}, {{"psi", psi}}, {{"pinned", pinned}});
    const VtuData back = read_vtu_data(path);
    auto same_bits = [](const double* a, const double* b, std::size_t n) { return std::memcmp(a, b, n * sizeof(double)) == 0; };
    ASSERT_EQ(back.mesh.mesh.vertices.cols(), Y.cols());
    EXPECT_TRUE(same_bits(back.mesh.mesh.vertices.data(), Y.data(), Y.size())) << "frame " << frame;
    EXPECT_EQ(back.mesh.mesh.cells, m.cells);
    const Eigen::Matrix3Xd u = Y - m.vertices;
    ASSERT_EQ(back.point_data.at("displacement").size(), static_cast<std::size_t>(u.size()));
    EXPECT_TRUE(same_bits(back.point_data.at("displacement").data(), u.data(), u.size()));
    EXPECT_TRUE(same_bits(back.point_data.at("pinned").data(), pinned.data(), pinned.size()));
    ASSERT_EQ(back.cell_data.at("psi").size(), 8u);
    EXPECT_TRUE(same_bits(back.cell_data.at("psi").data(), psi.data(), 8));
    if (frame == 1) {
      write_vtu(dir / "once.vtu", m, Y, {{"displacement", Y - m.vertices}}, {{"psi", psi}}, {{"pinned", pinned}});
      EXPECT_EQ(file_text(path), file_text(dir / "once.vtu"));
    }
  }
  fs::remove_all(dir);
}

TEST(Vtu, AnArrayOfTheWrongSizeIsRefused) {
  const fs::path dir = temp_dir("vtu_size");
  const VolumeMesh m = box_tets(1);
  auto error_of = [&](auto&& write) {
    try {
      write();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const VtuWriter w(m);
  EXPECT_EQ(error_of([&] { w.write(dir / "a.vtu", Eigen::Matrix3Xd::Zero(3, 7), {}, {}); }),
            (dir / "a.vtu").string() + ": the .vtu array Points has 7 values, expected 8");
  EXPECT_EQ(error_of([&] { w.write(dir / "b.vtu", m.vertices, {}, {{"J", Eigen::VectorXd::Zero(5)}}); }),
            (dir / "b.vtu").string() + ": the .vtu array J has 5 values, expected 6");
  EXPECT_EQ(error_of([&] { w.write(dir / "c.vtu", m.vertices, {{"u", Eigen::Matrix3Xd::Zero(3, 9)}}, {}); }),
            (dir / "c.vtu").string() + ": the .vtu array u has 9 values, expected 8");
  EXPECT_EQ(error_of([&] { w.write(dir / "d.vtu", m.vertices, {}, {}, {{"pinned", Eigen::VectorXd::Zero(1)}}); }),
            (dir / "d.vtu").string() + ": the .vtu array pinned has 1 values, expected 8");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 0) << "nothing written";
  fs::remove_all(dir);
}

TEST(Obj, VerticesAreWrittenAsPrintfsTenSignificantDigits) {
  // write_obj formats by std::to_chars: the characters must be printf's "%.10g" (the format the frames had).
  const std::vector<double> values = {0.0, -0.0, 1.0, -1.5, 0.1, 1.0 / 3.0, 123456789.123, 1234567890123.0, 1e-5,
                                      -2.5e-7, 1e-300, 5e-324, 1.7976931348623157e308, -9.999999999e-1, 0.00012345678901};
  Eigen::Matrix3Xd P(3, static_cast<Eigen::Index>(values.size()));
  for (std::size_t k = 0; k < values.size(); ++k) P.col(static_cast<Eigen::Index>(k)) << values[k], -values[k], values[k] * 7.0;
  Eigen::Matrix3Xi T(3, 1);
  T << 0, 1, 2;
  const fs::path dir = temp_dir("obj");
  write_obj(dir / "p.obj", P, T);
  std::string want;
  for (Eigen::Index v = 0; v < P.cols(); ++v) {
    char line[128];
    std::snprintf(line, sizeof line, "v %.10g %.10g %.10g\n", P(0, v), P(1, v), P(2, v));
    want += line;
  }
  want += "f 1 2 3\n";
  EXPECT_EQ(file_text(dir / "p.obj"), want);
  fs::remove_all(dir);
}

TEST(Obj, TextureCoordinatesAndNormalsAreWrittenPerVertexAndNamedByTheFaces) {
  Eigen::Matrix3Xd P(3, 3), N(3, 3);
  P << 0, 1, 0, 0, 0, 1, 0, 0, 0;
  N << 0, 0, 0, 0, 0, 0, 1, 1, 1;
  Eigen::Matrix2Xd UV(2, 3);
  UV << 0, 1, 0, 0, 0, 0.25;
  Eigen::Matrix3Xi T(3, 1);
  T << 0, 1, 2;
  const fs::path dir = temp_dir("obj_uv");
  write_obj(dir / "all.obj", P, UV, N, T);
  EXPECT_EQ(file_text(dir / "all.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 0.25\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1/1/1 2/2/2 3/3/3\n");
  write_obj(dir / "uv.obj", P, UV, Eigen::Matrix3Xd(3, 0), T);
  EXPECT_EQ(file_text(dir / "uv.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 0.25\nf 1/1 2/2 3/3\n");
  write_obj(dir / "n.obj", P, Eigen::Matrix2Xd(2, 0), N, T);
  EXPECT_EQ(file_text(dir / "n.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n");
  // The mesh readers take such a frame back (positions and triangles).
  const SurfaceMesh back = read_surface(dir / "all.obj");
  EXPECT_EQ(back.vertices, P);
  EXPECT_EQ(back.triangles, T);
  EXPECT_THROW(write_obj(dir / "bad.obj", P, Eigen::Matrix2Xd(2, 2), N, T), std::invalid_argument);
  fs::remove_all(dir);
}

TEST(AtomicFile, FailureNamesThePathAndLeavesNothing) {
  const fs::path dir = temp_dir("atomic");
  try {
    write_obj(dir / "missing" / "x.obj", Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xi(3, 0));
    FAIL() << "no error";
  } catch (const WriteError& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ensure_writable_directory("/proc/snh-cannot"), WriteError);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace snh
