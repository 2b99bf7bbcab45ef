// VTU frames: counts, VTK's hexahedron corner order (positive volume in VTK's convention), the data
// arrays, the .pvd series; and atomic writes leave no temporary files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "snh/io/atomic_file.hpp"
#include "snh/io/obj.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/surface.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The whitespace-separated numbers of the DataArray whose opening tag contains `name`.
std::vector<double> array_of(const std::string& xml, const std::string& name) {
  const auto tag = xml.find(name);
  if (tag == std::string::npos) return {};
  const auto start = xml.find('>', tag) + 1;
  const auto end = xml.find("</DataArray>", start);
  std::istringstream in(xml.substr(start, end - start));
  std::vector<double> out;
  for (double v; in >> v;) out.push_back(v);
  return out;
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
  const std::string xml = slurp(dir / "f.vtu");
  EXPECT_NE(xml.find("NumberOfPoints=\"27\" NumberOfCells=\"8\""), std::string::npos);
  const auto pts = array_of(xml, "NumberOfComponents=\"3\" format");
  ASSERT_EQ(pts.size(), 81u);
  const auto conn = array_of(xml, "Name=\"connectivity\"");
  ASSERT_EQ(conn.size(), 64u);
  EXPECT_EQ(array_of(xml, "Name=\"offsets\"").back(), 64);
  for (double t : array_of(xml, "Name=\"types\"")) EXPECT_EQ(t, 12);  // VTK_HEXAHEDRON
  for (int c = 0; c < 8; ++c) {
    auto p = [&](int a) {
      const int v = static_cast<int>(conn[8 * c + a]);
      return Eigen::Vector3d(pts[3 * v], pts[3 * v + 1], pts[3 * v + 2]);
    };
    // VTK: points 0-3 go around the bottom face, 4-7 above them: (p1−p0)×(p3−p0) points to p4.
    EXPECT_GT((p(1) - p(0)).cross(p(3) - p(0)).dot(p(4) - p(0)), 0.0) << "cell " << c;
    EXPECT_NEAR((p(2) - p(0)).norm(), std::sqrt(2.0) * 1.5, 1e-12);  // p2 is diagonal from p0
  }
  EXPECT_EQ(array_of(xml, "Name=\"J\"").size(), 8u);
  EXPECT_EQ(array_of(xml, "Name=\"displacement\"").size(), 81u);
  write_pvd(dir / "s.pvd", {{0.0, "f.vtu"}, {1.0, "g.vtu"}});
  const std::string pvd = slurp(dir / "s.pvd");
  EXPECT_NE(pvd.find("<DataSet timestep=\"1\" group=\"\" part=\"0\" file=\"g.vtu\"/>"), std::string::npos);
  // Nothing but the two files: the temporaries were renamed.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  fs::remove_all(dir);
}

TEST(Vtu, TetFrameTypes) {
  const fs::path dir = temp_dir("vtu_tet");
  const VolumeMesh m = box_tets(1);
  write_vtu(dir / "t.vtu", m, m.vertices, {}, {});
  const std::string xml = slurp(dir / "t.vtu");
  const auto types = array_of(xml, "Name=\"types\"");
  ASSERT_EQ(types.size(), 6u);
  for (double t : types) EXPECT_EQ(t, 10);  // VTK_TETRA
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
