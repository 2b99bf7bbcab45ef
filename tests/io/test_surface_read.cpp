// Surface meshes: OBJ, OFF, PLY and STL (ASCII and binary) read to the same cube, tetrahedralized by
// tetgen into a closed mesh of volume 1; one-line errors, including a missing tetgen program.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "snh/fem/rest_state.hpp"
#include "snh/io/surface_read.hpp"
#include "io/bytes_read.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

const double kCube[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
const int kQuads[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};  // outward

class SurfaceFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snh_test_surface_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return dir_ / name;
  }
  fs::path dir_;
};

/// The unit cube in every surface format: c.obj, c.off, c.ply, a.stl (ASCII) and b.stl (binary).
std::vector<std::pair<std::string, std::string>> cube_files() {
  std::string obj = "# cube\no cube\n", off = "OFF\n8 6 0\n", ply = "ply\nformat ascii 1.0\ncomment cube\nelement vertex 8\n"
                                                                  "property float x\nproperty float y\nproperty float z\n"
                                                                  "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
  std::string stl = "solid cube\n", bin(80, ' ');
  std::uint32_t count = 12;
  bin.append(reinterpret_cast<const char*>(&count), 4);
  for (const auto& p : kCube) {
    obj += fmt::format("v {} {} {}\nvn 0 0 1\n", p[0], p[1], p[2]);
    off += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
    ply += fmt::format("{} {} {}\n", p[0], p[1], p[2]);
  }
  for (const auto& q : kQuads) {
    obj += fmt::format("f {}//1 {}//1 {}//1 {}//1\n", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    off += fmt::format("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    ply += fmt::format("4 {} {} {} {}\n", q[0], q[1], q[2], q[3]);
    for (const auto& t : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      stl += "facet normal 0 0 0\nouter loop\n";
      float record[12] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const auto& p = kCube[t[k]];
        stl += fmt::format("vertex {} {} {}\n", p[0], p[1], p[2]);
        for (int a = 0; a < 3; ++a) record[3 + 3 * k + a] = static_cast<float>(p[a]);
      }
      stl += "endloop\nendfacet\n";
      bin.append(reinterpret_cast<const char*>(record), 48);
      bin.append(2, '\0');
    }
  }
  stl += "endsolid cube\n";
  return {{"c.obj", obj}, {"c.off", off}, {"c.ply", ply}, {"a.stl", stl}, {"b.stl", bin}};
}

TEST_F(SurfaceFiles, EveryFormatGivesTheCube) {
  for (const auto& [name, text] : cube_files()) {
    const SurfaceMesh s = read_surface(write(name, text));
    EXPECT_EQ(s.vertices.cols(), 8) << name;
    EXPECT_EQ(s.triangles.cols(), 12) << name;
    const MeshFile m = read_mesh(dir_ / name);  // through tetgen
    EXPECT_EQ(m.mesh.type, CellType::tet4) << name;
    EXPECT_GE(m.mesh.cell_count(), 5) << name;
    EXPECT_NEAR(rest_volumes(compute_rest_state(m.mesh)).sum(), 1.0, 1e-12) << name;
  }
}

// An OBJ file's vertex normals: each vertex gets the first normal its corners name (v//vn and v/vt/vn,
// negative indices too); none at all when a vertex has none, or in the other formats.
TEST_F(SurfaceFiles, ObjNormalsBelongToTheirVertices) {
  const SurfaceMesh s = read_surface(write("n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 -1\nvt 0 0\n"
                                                      "f 1//2 2/1/1 3/1/-1\nf 1//1 3//1 2//1\n"));
  ASSERT_EQ(s.normals.cols(), 3);
  EXPECT_EQ(s.normals.col(0), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(s.normals.col(1), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(s.normals.col(2), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(read_surface(write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3\n")).normals.cols(), 0);
  EXPECT_EQ(read_surface(write("c.off", cube_files().at(1).second)).normals.cols(), 0);
}

TEST_F(SurfaceFiles, ErrorsAreOneLine) {
  auto error = [&](const std::string& name, const std::string& text) {
    try {
      (void)read_mesh(write(name, text));
    } catch (const MeshError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      return msg.substr((dir_ / name).string().size());
    }
    return std::string();
  };
  EXPECT_EQ(error("a.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n"), ":3: face refers to vertex 3, but there are 2");
  EXPECT_EQ(error("b.obj", "v 0 0 nan\n"), ":1: a coordinate is not finite: 'nan'");
  EXPECT_EQ(error("b2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n"), ":5: face refers to normal 2, but there are 1");
  EXPECT_EQ(error("b3.obj", "vn 0 x 1\n"), ":1: expected a normal's coordinate (a number), got 'x'");
  EXPECT_EQ(error("c.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n"), ":5: the file ends where a coordinate was expected");
  EXPECT_EQ(error("d.ply", "ply\nformat binary_little_endian 1.0\n"), ":2: PLY format 'binary_little_endian' is not supported (ascii is)");
  EXPECT_EQ(error("e.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n"), ":5: the file ends where z was expected");
  EXPECT_NE(error("f.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").find("tetgen could not tetrahedralize the surface"),
            std::string::npos);
  // Without the tetgen program: a clear error naming the Debian package.
  const std::string saved = std::getenv("PATH") ? std::getenv("PATH") : "";
  ::setenv("PATH", "/nonexistent", 1);
  const std::string missing = error("g.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(missing.find("Debian package tetgen"), std::string::npos) << missing;
  // A tetgen that crashes (as TetGen does on some surfaces, throwing an int): the crash is named, not the C++
  // runtime's line. A stand-in program on PATH does what it does.
  const fs::path bin = dir_ / "bin";
  fs::create_directories(bin);
  std::ofstream(bin / "tetgen") << "#!/bin/sh\necho \"terminate called after throwing an instance of 'int'\"\nkill -ABRT $$\n";
  fs::permissions(bin / "tetgen", fs::perms::owner_all);
  ::setenv("PATH", (bin.string() + ":" + saved).c_str(), 1);
  const std::string crashed = error("h.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_NE(crashed.find("tetgen crashed (Aborted)"), std::string::npos) << crashed;
  EXPECT_EQ(crashed.find("terminate called"), std::string::npos) << crashed;
}

// A surface followed by 900 MB of NUL bytes (a sparse file) fails after reading about as much as the
// surface; a binary STL's triangle count is checked against its size, and an ASCII one's first word, before
// the rest is read.
TEST_F(SurfaceFiles, APaddedFileIsReadOnlyUpToItsPadding) {
  if (test::bytes_read() < 0) GTEST_SKIP() << "no /proc/self/io";
  for (const auto& [name, text] : cube_files()) {
    const fs::path p = write(name, text);
    fs::resize_file(p, 900u << 20);
    const long long before = test::bytes_read();
    std::string error;
    try {
      (void)read_surface(p);
    } catch (const MeshError& e) {
      error = std::string(e.what()).substr(p.string().size());
    }
    const long long read = test::bytes_read() - before;
    if (name == "b.stl")
      EXPECT_EQ(error, ":1: not an STL file: it does not start with 'solid' (ASCII), and as binary STL its count of 12 triangles "
                       "needs 84 + 50 x 12 = 684 bytes, not 943718400");
    else
      EXPECT_TRUE(error.find("binary data (a NUL byte) where text was expected") != std::string::npos ||
                  error.find("more data than the header announces") != std::string::npos)
          << name << ": " << error;
    EXPECT_LT(read, 8 << 20) << name << ": read " << read << " bytes";
  }
  auto error = [&](const std::string& name, const std::string& text) {
    try {
      (void)read_surface(write(name, text));
    } catch (const MeshError& e) {
      return std::string(e.what()).substr((dir_ / name).string().size());
    }
    return std::string();
  };
  EXPECT_EQ(error("short.stl", "facet"), ":1: not an STL file: it does not start with 'solid' (ASCII) and its 5 bytes are fewer than a binary STL's 84");
  EXPECT_EQ(error("solidx.stl", "solidx\n" + std::string(100, 'x')).substr(0, 47), ":1: not an STL file: it does not start with 'so");
}

}  // namespace
}  // namespace snh
