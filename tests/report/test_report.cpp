// The browser report's data, checked against the run it describes: the .vtu data arrays read
// back, the surface (counts, cells, rest positions), every frame's positions and fields against the
// .vtu frames, the legend ranges against stats.json, the plots' lengths, a flesh run's render surface
// and bones against its files, the lab's tables and links, and one-line errors for directories it
// cannot describe (a flesh run's files at fault named).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/mesh_read.hpp"
#include "snh/io/obj.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/box.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/report/render.hpp"
#include "snh/report/report.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/setup/lab.hpp"
#include "snh/setup/scene_run.hpp"
#include "snh/setup/stretch.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

fs::path report_dir(const std::string& name) { return test::fresh_dir("snh_report_", name); }

/// Removes every directory made by report_dir when the test program ends, also after a failed ASSERT.
struct CleanUp : ::testing::Environment {
  void TearDown() override {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::temp_directory_path(), ec))
      if (e.path().filename().string().rfind("snh_report_", 0) == 0 &&
          e.path().filename().string().ends_with("_" + std::to_string(::getpid())))
        fs::remove_all(e.path(), ec);
  }
};
[[maybe_unused]] const auto* const kCleanUp = ::testing::AddGlobalTestEnvironment(new CleanUp);

using test::file_text;

/// The JSON of `prefix ... suffix` in a file (data.js: "window.SNH_REPORT = {...};").
json js_payload(const fs::path& p, const std::string& prefix, const std::string& suffix) {
  const std::string text = file_text(p);
  EXPECT_EQ(text.compare(0, prefix.size(), prefix), 0) << p;
  const std::size_t end = text.rfind(suffix);
  return json::parse(text.substr(prefix.size(), end - prefix.size()));
}

std::vector<unsigned char> base64_decode(const std::string& s) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::vector<unsigned char> out;
  unsigned buffer = 0;
  int bits = 0;
  for (char c : s) {
    if (c == '=') break;
    buffer = (buffer << 6) | static_cast<unsigned>(value(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buffer >> bits) & 0xFF));
    }
  }
  return out;
}

template <class T>
std::vector<T> decode(const json& b64) {
  const auto bytes = base64_decode(b64.get<std::string>());
  EXPECT_EQ(bytes.size() % sizeof(T), 0u);
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

TEST(VtuData, ReadsBackEveryArrayOfAFrame) {
  const fs::path dir = report_dir("vtu");
  fs::create_directories(dir);
  const VolumeMesh m = box_hexes(2);
  const Eigen::Matrix3Xd X = m.vertices * 1.25;
  Eigen::VectorXd J(m.cell_count()), psi(m.cell_count()), pinned = Eigen::VectorXd::Zero(m.vertex_count());
  for (Eigen::Index c = 0; c < m.cell_count(); ++c) J[c] = 0.5 + 0.125 * c, psi[c] = c;
  psi[3] = std::numeric_limits<double>::infinity();
  pinned[4] = 1;
  write_vtu(dir / "f.vtu", m, X, {{"displacement", X - m.vertices}}, {{"J", J}, {"psi", psi}}, {{"pinned", pinned}});
  const VtuData d = read_vtu_data(dir / "f.vtu");
  ASSERT_EQ(d.mesh.mesh.cell_count(), m.cell_count());
  EXPECT_TRUE(d.mesh.mesh.cells == m.cells);  // VTK's hex order turned back into ours
  ASSERT_EQ(d.point_data.at("displacement").size(), 3u * m.vertex_count());
  EXPECT_DOUBLE_EQ(d.point_data.at("displacement")[3 * 26 + 2], 0.25);
  ASSERT_EQ(d.point_data.at("pinned").size(), static_cast<std::size_t>(m.vertex_count()));
  EXPECT_EQ(d.point_data.at("pinned")[4], 1.0);
  ASSERT_EQ(d.cell_data.at("J").size(), static_cast<std::size_t>(m.cell_count()));
  EXPECT_DOUBLE_EQ(d.cell_data.at("J")[7], 1.375);
  EXPECT_TRUE(std::isinf(d.cell_data.at("psi")[3]));  // an undefined energy density survives the round trip
  fs::remove_all(dir);
}

/// A small stretch run and its report.
struct StretchRun {
  fs::path dir;
  StretchResult result;
  json data;
};

StretchRun stretch_run(CellType element, const std::string& name) {
  StretchRun r;
  StretchConfig c;
  c.element = element;
  c.resolution = 3;
  c.steps = 5;
  c.stretch = 2.0;
  c.out = r.dir = report_dir(name);
  c.command_line = "snh stretch --res 3 --steps 5 --stretch 2";
  std::ostringstream log;
  r.result = run_stretch(c, log);
  const ReportSummary s = write_report(r.dir);
  EXPECT_EQ(s.kind, "stretch");
  EXPECT_EQ(s.frames, 6);
  EXPECT_EQ(s.index, r.dir / "index.html");
  r.data = js_payload(r.dir / "report" / "data.js", "window.SNH_REPORT = ", ";");
  return r;
}

TEST(RunReport, StretchRunSurfaceFramesAndRanges) {
  for (CellType element : {CellType::tet4, CellType::hex8}) {
    const StretchRun run = stretch_run(element, element == CellType::tet4 ? "tet" : "hex");
    ASSERT_TRUE(run.result.all_converged);
    const json& d = run.data;
    EXPECT_EQ(d["kind"], "stretch");
    EXPECT_EQ(d["title"], "snh stretch --res 3 --steps 5 --stretch 2");
    EXPECT_TRUE(d["status"]["ok"].get<bool>());
    EXPECT_EQ(d["status"]["text"], "converged every step");  // nothing to warn of
    EXPECT_EQ(d["status"]["warnings"], json::array());
    const json& mesh = d["mesh"];
    const int res = 3, nv = (res + 1) * (res + 1) * (res + 1);
    EXPECT_EQ(mesh["vertex_count"], nv);
    EXPECT_EQ(mesh["cell_count"], element == CellType::tet4 ? 6 * 27 : 27);
    EXPECT_EQ(mesh["pinned_count"], 2 * (res + 1) * (res + 1));  // the two pulled layers
    const json& surf = mesh["surface"];
    const int tris = 12 * res * res, ns = nv - (res - 1) * (res - 1) * (res - 1);
    EXPECT_EQ(surf["triangle_count"], tris);
    EXPECT_EQ(surf["vertex_count"], ns);
    const auto tri = decode<std::uint32_t>(surf["triangles"]);
    const auto tri_cell = decode<std::uint32_t>(surf["triangle_cells"]);
    const auto rest = decode<float>(surf["rest"]);
    const auto pinned = decode<std::uint8_t>(surf["pinned"]);
    ASSERT_EQ(tri.size(), 3u * tris);
    ASSERT_EQ(tri_cell.size(), static_cast<std::size_t>(tris));
    ASSERT_EQ(rest.size(), 3u * ns);
    ASSERT_EQ(pinned.size(), static_cast<std::size_t>(ns));
    const int m = surf["cell_count"];
    for (std::uint32_t t : tri) ASSERT_LT(t, static_cast<std::uint32_t>(ns));
    for (std::uint32_t c : tri_cell) ASSERT_LT(c, static_cast<std::uint32_t>(m));
    // Pinned surface vertices are exactly those at rest y = ±1, and the rest box is [-1, 1]^3.
    int pinned_seen = 0;
    for (int k = 0; k < ns; ++k) {
      EXPECT_EQ(pinned[k] != 0, std::abs(std::abs(rest[3 * k + 1]) - 1.0f) < 1e-6f) << k;
      pinned_seen += pinned[k];
      for (int a = 0; a < 3; ++a) EXPECT_LE(std::abs(rest[3 * k + a]), 1.0f + 1e-6f);
    }
    EXPECT_EQ(pinned_seen, 2 * (res + 1) * (res + 1));

    // Frames: the positions are the .vtu frame's surface points; the fields its cell values.
    const json& frames = mesh["frames"];
    ASSERT_EQ(frames.size(), 6u);
    double min_J = 1.0, max_J = -1e300, max_disp = 0.0;
    for (const json& f : frames) {
      const int i = f["index"];
      EXPECT_EQ(f["label"], fmt::format("step {}", i));
      EXPECT_EQ(f["time"].get<double>(), i);
      const json fd = js_payload(run.dir / f["src"].get<std::string>(), fmt::format("snhReportFrame({}, ", i), ");");
      const VtuData vtu = read_vtu_data(run.dir / fmt::format("{:03d}.vtu", i));
      const auto x = decode<float>(fd["x"]), J = decode<float>(fd["J"]), psi = decode<float>(fd["psi"]),
                 disp = decode<float>(fd["displacement"]);
      ASSERT_EQ(x.size(), 3u * ns);
      ASSERT_EQ(J.size(), static_cast<std::size_t>(m));
      ASSERT_EQ(psi.size(), static_cast<std::size_t>(m));
      ASSERT_EQ(disp.size(), static_cast<std::size_t>(ns));
      // Each surface vertex: find it among the .vtu points by its rest position (x − displacement).
      const auto& D = vtu.point_data.at("displacement");
      std::vector<int> global(ns, -1);
      for (int k = 0; k < ns; ++k) {
        int found = -1;
        for (Eigen::Index v = 0; v < vtu.mesh.mesh.vertex_count(); ++v) {
          const Eigen::Vector3d X = vtu.mesh.mesh.vertices.col(v) - Eigen::Vector3d(D[3 * v], D[3 * v + 1], D[3 * v + 2]);
          if ((X - Eigen::Vector3d(rest[3 * k], rest[3 * k + 1], rest[3 * k + 2])).norm() < 1e-6) found = static_cast<int>(v);
        }
        ASSERT_GE(found, 0) << "frame " << i << " surface vertex " << k;
        global[k] = found;
        for (int a = 0; a < 3; ++a) EXPECT_NEAR(x[3 * k + a], vtu.mesh.mesh.vertices(a, found), 1e-6);
        const double d = Eigen::Vector3d(D[3 * found], D[3 * found + 1], D[3 * found + 2]).norm();
        EXPECT_NEAR(disp[k], d, 1e-6);
      }
      // Each triangle shows the fields of the one cell that has all three of its corners.
      const VolumeMesh& vm = vtu.mesh.mesh;
      for (int t = 0; t < tris; ++t) {
        int owner = -1, owners = 0;
        for (Eigen::Index c = 0; c < vm.cell_count(); ++c) {
          int corners = 0;
          for (int a = 0; a < 3; ++a)
            for (Eigen::Index n = 0; n < vm.cells.rows(); ++n) corners += vm.cells(n, c) == global[tri[3 * t + a]];
          if (corners == 3) owner = static_cast<int>(c), ++owners;
        }
        ASSERT_EQ(owners, 1) << "frame " << i << " triangle " << t;
        EXPECT_NEAR(J[tri_cell[t]], vtu.cell_data.at("J")[owner], 1e-6) << "frame " << i << " triangle " << t;
        EXPECT_NEAR(psi[tri_cell[t]], vtu.cell_data.at("psi")[owner], 1e-6 * (1 + std::abs(psi[tri_cell[t]])));
      }
      for (double v : vtu.cell_data.at("J")) min_J = std::min(min_J, v), max_J = std::max(max_J, v);
      for (std::size_t v = 0; v < D.size() / 3; ++v)
        max_disp = std::max(max_disp, Eigen::Vector3d(D[3 * v], D[3 * v + 1], D[3 * v + 2]).norm());
      for (float j : J) EXPECT_GT(j, 0.0f);
    }
    // The legend ranges cover every cell of every frame: J's minimum is stats.json's smallest min_J.
    double stats_min_J = 1.0;
    for (const StepStats& s : run.result.steps) stats_min_J = std::min(stats_min_J, s.min_J);
    const json& J = mesh["fields"][0];
    ASSERT_EQ(J["name"], "J");
    EXPECT_NEAR(J["min"].get<double>(), stats_min_J, 1e-9);
    EXPECT_NEAR(J["min"].get<double>(), min_J, 1e-12);
    EXPECT_NEAR(J["max"].get<double>(), max_J, 1e-12);
    EXPECT_EQ(mesh["fields"][1]["name"], "psi");
    EXPECT_EQ(mesh["fields"][1]["min"].get<double>(), mesh["fields"][1]["min"].get<double>());  // finite
    EXPECT_NEAR(mesh["fields"][2]["max"].get<double>(), max_disp, 1e-9);
    EXPECT_NEAR(mesh["fields"][2]["max"].get<double>(), 1.0, 1e-9);  // the pulled layers move by (2 − 1) · 1

    // Plots: one point per step.
    for (const json& p : d["plots"]) {
      EXPECT_EQ(p["x"].size(), 5u) << p["id"];
      for (const json& s : p["series"]) EXPECT_EQ(s["y"].size(), 5u) << p["id"];
    }
    // The page loads the data, then the bundle, which is written beside it.
    const std::string html = file_text(run.dir / "index.html");
    EXPECT_LT(html.find("report/data.js"), html.find("report/snh-report.js"));
    EXPECT_EQ(file_text(run.dir / "report" / "snh-report.js"), std::string(report_bundle()));
    EXPECT_GT(report_bundle().size(), 10000u);
    fs::remove_all(run.dir);
  }
}

TEST(RunReport, RewritingForFewerFramesRemovesStaleFrameFiles) {
  StretchRun run = stretch_run(CellType::hex8, "stale");
  // Keep only frames 0 to 2 in the series, as after a shorter run in the same directory.
  write_pvd(run.dir / "frames.pvd", {{0.0, "000.vtu"}, {1.0, "001.vtu"}, {2.0, "002.vtu"}});
  const ReportSummary s = write_report(run.dir);
  EXPECT_EQ(s.frames, 3);
  EXPECT_TRUE(fs::exists(run.dir / "report" / "frames" / "002.js"));
  EXPECT_FALSE(fs::exists(run.dir / "report" / "frames" / "003.js"));
  fs::remove_all(run.dir);
}

/// A 2x2x2 hex bar hanging from its top face under gravity, 4 frames to t = 0.2, into report_dir(name).
Scene hanging_scene(const std::string& name, const std::string& command_line) {
  Scene s;
  s.mesh.element = CellType::hex8;
  s.mesh.resolution = 2;
  s.time.end_time = 0.2;
  s.time.frames = 4;
  s.forces.gravity = Eigen::Vector3d(0, -9.8, 0);
  PinSpec pin;
  pin.select.region = Eigen::AlignedBox3d(Eigen::Vector3d(-1, 1, -1), Eigen::Vector3d(1, 1, 1));  // the top face
  s.pins.push_back(pin);
  s.output.dir = report_dir(name);
  s.run.command_line = command_line;
  return s;
}

TEST(RunReport, SceneReportUsesTimeAndItsPins) {
  const Scene s = hanging_scene("scene", "snh run hanging.json");
  std::ostringstream log;
  const SceneResult r = run_scene(s, log);
  ASSERT_TRUE(r.all_converged);
  const ReportSummary sum = write_report(s.output.dir);
  EXPECT_EQ(sum.kind, "scene");
  EXPECT_EQ(sum.frames, 5);
  const json d = js_payload(s.output.dir / "report" / "data.js", "window.SNH_REPORT = ", ";");
  EXPECT_EQ(d["title"], "snh run hanging.json");
  EXPECT_TRUE(d["render"].is_null());  // not a flesh run
  EXPECT_EQ(d["mesh"]["pinned_count"], 9);
  EXPECT_EQ(d["mesh"]["frames"][4]["label"], "frame 4");
  EXPECT_NEAR(d["mesh"]["frames"][4]["time"].get<double>(), 0.2, 1e-12);
  for (const json& p : d["plots"]) {
    EXPECT_EQ(p["x"].size(), 5u);  // frame 0 included
    EXPECT_EQ(p["x_label"], "time");
  }
  fs::remove_all(s.output.dir);
}

/// A flesh-like run directory: a small scene run, then what a flesh run adds (surface/ and lbs/ frames of an
/// octahedron, bones.json, flesh.usda, and stats.json's flesh keys and render volumes), as `snh flesh` writes them.
struct FleshRun {
  fs::path dir;
  int frames = 0;
  Eigen::Matrix3Xi triangles;
  std::vector<Eigen::Matrix3Xd> flesh, lbs;
  std::vector<std::string> bones = {"shoulder>elbow", "wrist"};
  std::vector<std::vector<double>> segments;  ///< per frame, 6 per bone
};

FleshRun flesh_run(const std::string& name) {
  FleshRun f;
  const Scene s = hanging_scene(name, "snh flesh arm.glb");
  f.dir = s.output.dir;
  std::ostringstream log;
  const SceneResult r = run_scene(s, log);
  EXPECT_TRUE(r.all_converged);
  f.frames = static_cast<int>(r.frames.size());

  Eigen::Matrix3Xd octahedron(3, 6);
  octahedron << 0.5, -0.5, 0, 0, 0, 0,  //
      0, 0, 0.5, -0.5, 0, 0,            //
      0, 0, 0, 0, 0.5, -0.5;
  f.triangles.resize(3, 8);
  f.triangles << 0, 2, 1, 3, 0, 3, 1, 2,  //
      2, 1, 3, 0, 3, 1, 2, 0,             //
      4, 4, 4, 4, 5, 5, 5, 5;
  fs::create_directories(f.dir / "surface");
  fs::create_directories(f.dir / "lbs");
  json bone_frames = json::array();
  for (int i = 0; i < f.frames; ++i) {
    f.flesh.push_back(octahedron * (1.0 + 0.1 * i));
    f.lbs.push_back((octahedron * (1.0 - 0.05 * i)).colwise() + Eigen::Vector3d(0.0, -0.02 * i, 0.0));
    write_obj(f.dir / "surface" / fmt::format("{:03d}.obj", i), f.flesh.back(), f.triangles);
    write_obj(f.dir / "lbs" / fmt::format("{:03d}.obj", i), f.lbs.back(), f.triangles);
    f.segments.push_back({0.0, 0.4, 0.0, 0.1 * i, -0.4, 0.0, 0.3, -0.6 - 0.1 * i, 0.0, 0.3, -0.6 - 0.1 * i, 0.0});
    bone_frames.push_back({{"time", 0.05 * i},
                           {"segments", {std::vector<double>(f.segments[i].begin(), f.segments[i].begin() + 6),
                                         std::vector<double>(f.segments[i].begin() + 6, f.segments[i].end())}}});
  }
  std::ofstream(f.dir / "bones.json") << json{{"bones", f.bones}, {"frames", bone_frames}}.dump() << "\n";
  std::ofstream(f.dir / "flesh.usda") << "#usda 1.0\n";
  json stats = json::parse(file_text(f.dir / "stats.json"));
  for (json& row : stats["frames"]) {
    const int i = row["frame"];
    row["surface_volume_ratio"] = 1.0 - 0.001 * i;
    row["lbs_volume_ratio"] = 1.0 - 0.02 * i;
  }
  stats["schema"]["columns"].push_back({{"key", "surface_volume_ratio"}, {"label", "flesh"}, {"plot", "render_volume"}});
  stats["schema"]["columns"].push_back(
      {{"key", "lbs_volume_ratio"}, {"label", "linear blend skinning"}, {"plot", "render_volume"}});
  stats["schema"]["plots"].push_back({{"id", "render_volume"},
                                      {"title", "Volume inside the render surface (posed / rest)"},
                                      {"y_label", "ratio"},
                                      {"log_y", false}});
  stats["model"] = "arm.glb";
  stats["volume"] = "lattice";
  stats["animation"] = "wave";
  stats["bound_vertices"] = 9;
  stats["bones"] = {{{"name", "shoulder>elbow"}, {"radius", 0.2}, {"bound", 9}},
                    {{"name", "wrist"}, {"radius", 0.1}, {"bound", 0}}};
  stats["usd"] = "flesh.usda";
  stats["radius_scale"] = 0.6;
  stats["pressed_flesh"] = {{"frames", 2}, {"worst_frame", 4}, {"time", 0.2}, {"bones", {"shoulder>elbow", "elbow>wrist"}},
                            {"rest_distance", 0.5}, {"closest", 0.01}};
  stats["warnings"] = {"the bones press flesh inside out in 2 frames", "2 frames converged with elements turned inside out"};
  std::ofstream(f.dir / "stats.json") << stats.dump(2) << "\n";
  return f;
}

/// The distance in millimetres (a surface in metres) from p to the nearest triangle of a surface, by brute force
/// with IPC's point–triangle distance: what the report's distances are checked against.
double nearest_mm(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& vertices, const Eigen::Matrix3Xi& triangles) {
  double nearest = 1e300;
  for (Eigen::Index t = 0; t < triangles.cols(); ++t)
    nearest = std::min(nearest, contact::point_triangle_distance(p, vertices.col(triangles(0, t)), vertices.col(triangles(1, t)),
                                                                 vertices.col(triangles(2, t))));
  return 1000.0 * std::sqrt(nearest);
}

/// The value of the meta line `label` ("" when there is none).
json meta_value(const json& d, const std::string& label) {
  for (const json& m : d["meta"])
    if (m[0] == label) return m[1];
  return "";
}

TEST(RunReport, FleshRunRenderSurfaceBonesAndSettings) {
  const FleshRun f = flesh_run("flesh");
  ASSERT_EQ(f.frames, 5);
  const ReportSummary sum = write_report(f.dir);
  EXPECT_EQ(sum.frames, 5);
  const json d = js_payload(f.dir / "report" / "data.js", "window.SNH_REPORT = ", ";");
  const json& r = d["render"];
  ASSERT_TRUE(r.is_object());
  EXPECT_EQ(r["vertex_count"], 6);
  EXPECT_EQ(r["triangle_count"], 8);
  const auto tri = decode<std::uint32_t>(r["triangles"]);
  ASSERT_EQ(tri.size(), 24u);
  for (int t = 0; t < 8; ++t)
    for (int a = 0; a < 3; ++a) EXPECT_EQ(tri[3 * t + a], static_cast<std::uint32_t>(f.triangles(a, t)));
  EXPECT_EQ(r["bones"], json(f.bones));

  // Each frame's file: the flesh and skinned positions of its OBJ files, and the bones of bones.json.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int i = 0; i < f.frames; ++i) {
    const json fd =
        js_payload(f.dir / d["mesh"]["frames"][i]["src"].get<std::string>(), fmt::format("snhReportFrame({}, ", i), ");");
    const auto flesh = decode<float>(fd["render"]["flesh"]), lbs = decode<float>(fd["render"]["lbs"]),
               bones = decode<float>(fd["render"]["bones"]);
    ASSERT_EQ(flesh.size(), 18u);
    ASSERT_EQ(lbs.size(), 18u);
    ASSERT_EQ(bones.size(), 12u);
    for (int v = 0; v < 6; ++v)
      for (int a = 0; a < 3; ++a) {
        EXPECT_NEAR(flesh[3 * v + a], f.flesh[i](a, v), 1e-6) << "frame " << i;
        EXPECT_NEAR(lbs[3 * v + a], f.lbs[i](a, v), 1e-6) << "frame " << i;
        for (const Eigen::Matrix3Xd* x : {&f.flesh[i], &f.lbs[i]}) {
          lo[a] = std::min(lo[a], (*x)(a, v));
          hi[a] = std::max(hi[a], (*x)(a, v));
        }
      }
    for (int k = 0; k < 12; ++k) {
      EXPECT_NEAR(bones[k], f.segments[i][k], 1e-6) << "frame " << i;
      lo[k % 3] = std::min(lo[k % 3], f.segments[i][k]);
      hi[k % 3] = std::max(hi[k % 3], f.segments[i][k]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(r["bounds"]["min"][a].get<double>(), lo[a], 1e-9);
    EXPECT_NEAR(r["bounds"]["max"][a].get<double>(), hi[a], 1e-9);
  }

  // Each flesh vertex's signed distance from the skinned surface, in millimetres (stats.json gives no unit: metres):
  // the nearest of every triangle (IPC's distance, brute force), outside (the flesh grows, the skin shrinks), zero
  // in frame 0 where the two are one surface; its range over the frames, and the largest per frame as a plot.
  double largest = 0.0;
  std::vector<double> outside(f.frames, 0.0);
  for (int i = 0; i < f.frames; ++i) {
    const json fd = js_payload(f.dir / d["mesh"]["frames"][i]["src"].get<std::string>(), fmt::format("snhReportFrame({}, ", i), ");");
    const auto dist = decode<float>(fd["render"]["distance"]);
    ASSERT_EQ(dist.size(), 6u);
    for (int v = 0; v < 6; ++v) {
      const double expected = nearest_mm(f.flesh[i].col(v), f.lbs[i], f.triangles);
      EXPECT_NEAR(dist[v], expected, 1e-6 * (1.0 + expected)) << "frame " << i << " vertex " << v;
      if (i == 0) {
        EXPECT_EQ(dist[v], 0.0f) << "vertex " << v;
      }
      largest = std::max(largest, expected);
      outside[i] = std::max(outside[i], expected);
    }
  }
  EXPECT_NEAR(r["distance"]["max"].get<double>(), largest, 1e-9 * largest);
  EXPECT_EQ(r["distance"]["min"].get<double>(), 0.0);
  EXPECT_EQ(r["distance"]["unit"], "mm");
  EXPECT_EQ(decode<std::uint32_t>(r["normal_groups"]), (std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5}));
  const json* distance_plot = nullptr;
  for (const json& p : d["plots"])
    if (p["id"] == "lbs_surface_distance") distance_plot = &p;
  ASSERT_NE(distance_plot, nullptr);
  for (int i = 0; i < f.frames; ++i) {
    EXPECT_NEAR((*distance_plot)["series"][0]["y"][i].get<double>(), outside[i], 1e-9 * (1.0 + outside[i])) << "frame " << i;
    EXPECT_EQ((*distance_plot)["series"][1]["y"][i].get<double>(), 0.0) << "frame " << i;
  }
  EXPECT_EQ(r["up_axis"], "+Y");

  // The render volumes: one plot, both curves, one point per frame.
  const json* render_volume = nullptr;
  for (const json& p : d["plots"])
    if (p["id"] == "render_volume") render_volume = &p;
  ASSERT_NE(render_volume, nullptr);
  ASSERT_EQ((*render_volume)["series"].size(), 2u);
  EXPECT_EQ((*render_volume)["series"][0]["label"], "flesh");
  EXPECT_EQ((*render_volume)["series"][1]["label"], "linear blend skinning");
  EXPECT_NEAR((*render_volume)["series"][1]["y"][4].get<double>(), 0.92, 1e-12);

  // The settings of a flesh run, and the USD stage linked.
  EXPECT_EQ(meta_value(d, "model"), "arm.glb");
  EXPECT_EQ(meta_value(d, "animation"), "wave");
  EXPECT_EQ(meta_value(d, "flesh volume"), "hexahedral lattice (lattice)");
  EXPECT_EQ(meta_value(d, "resolution"), "2");
  EXPECT_EQ(meta_value(d, "bound vertices"), "9");
  EXPECT_EQ(meta_value(d, "bones"), "2 (binding no vertex: wrist)");
  EXPECT_EQ(meta_value(d, "capsule radii"), "0.6 x the default");
  EXPECT_EQ(meta_value(d, "warning: bones press flesh inside out"), "");  // listed under the status instead (below)
  EXPECT_EQ(meta_value(d, "USD stage"), (json{{"text", "flesh.usda"}, {"href", "flesh.usda"}}));
  // The run's warnings: the status says how many, and the page lists them.
  EXPECT_TRUE(d["status"]["ok"].get<bool>());
  EXPECT_EQ(d["status"]["text"], "finished with 2 warnings");
  EXPECT_EQ(d["status"]["warnings"],
            (json{"the bones press flesh inside out in 2 frames", "2 frames converged with elements turned inside out"}));
  fs::remove(f.dir / "flesh.usda");
  (void)write_report(f.dir);
  EXPECT_EQ(meta_value(read_report_data(f.dir), "USD stage"), "");  // no link to a file that is not there

  // A run from before stats.json listed its warnings: the pressed flesh among the settings, a plain status.
  json stats = json::parse(test::file_text(f.dir / "stats.json"));
  stats.erase("warnings");
  std::ofstream(f.dir / "stats.json") << stats.dump(2) << "\n";
  (void)write_report(f.dir);
  const json older = read_report_data(f.dir);
  EXPECT_EQ(meta_value(older, "warning: bones press flesh inside out"),
            "in 2 frame(s); worst frame 4: shoulder>elbow and elbow>wrist carry bound vertices 0.5 apart at rest to 0.01 (their "
            "capsules overlap; smaller radii leave the flesh room)");
  EXPECT_EQ(older["status"]["text"], "finished");
  EXPECT_EQ(older["status"]["warnings"], json::array());

  // Without bones.json, the surfaces alone.
  fs::remove(f.dir / "bones.json");
  (void)write_report(f.dir);
  const json without = read_report_data(f.dir);
  EXPECT_TRUE(without["render"]["bones"].is_null());
  EXPECT_FALSE(js_payload(f.dir / "report" / "frames" / "002.js", "snhReportFrame(2, ", ");")["render"].contains("bones"));
  fs::remove_all(f.dir);
}

TEST(RunReport, FleshRunFilesAtFaultAreNamedInOneLine) {
  const FleshRun f = flesh_run("flesh_errors");
  auto message = [&] {
    try {
      (void)write_report(f.dir);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // One line that starts with the file at fault.
  auto starts = [](const std::string& m, const fs::path& p) {
    return m.rfind(p.string() + ":", 0) == 0 && m.find('\n') == std::string::npos;
  };
  ASSERT_EQ(message(), "no error");
  const fs::path s2 = f.dir / "surface" / "002.obj", l3 = f.dir / "lbs" / "003.obj", bones = f.dir / "bones.json";
  const std::string good_s2 = file_text(s2), good_l3 = file_text(l3), good_bones = file_text(bones);

  std::ofstream(s2) << "v 0 0 0\nv 1 0 x\n";  // malformed
  std::string m = message();
  EXPECT_TRUE(starts(m, s2)) << m;
  EXPECT_NE(m.find(":2:"), std::string::npos) << m;
  std::ofstream(s2) << good_s2.substr(0, good_s2.find("\nf ") + 1);  // cut short: no triangles
  m = message();
  EXPECT_TRUE(starts(m, s2)) << m;
  std::ofstream(s2) << "v 0 0 0\n" << good_s2;  // a vertex too many
  EXPECT_EQ(message(), s2.string() + ": 7 vertices and 8 triangles, but surface/000.obj has 6 and 8");
  std::ofstream(s2) << good_s2;

  fs::remove(l3);
  m = message();
  EXPECT_TRUE(starts(m, l3)) << m;
  EXPECT_NE(m.find("frame 3 (003.vtu)"), std::string::npos) << m;
  std::string flipped = good_l3;  // the same counts, another triangle
  flipped.replace(flipped.rfind("f "), std::string::npos, "f 1 2 6\n");
  std::ofstream(l3) << flipped;
  EXPECT_EQ(message(), l3.string() + ": its triangles are not those of surface/000.obj");
  std::ofstream(l3) << good_l3;

  std::ofstream(bones) << good_bones.substr(0, good_bones.size() / 2);
  m = message();
  EXPECT_TRUE(starts(m, bones) && m.find("not valid JSON") != std::string::npos) << m;
  json b = json::parse(good_bones);
  b["frames"].erase(b["frames"].begin() + 1);
  std::ofstream(bones) << b.dump();
  EXPECT_EQ(message(), bones.string() + ": 4 frames, but frames.pvd has 5");
  b = json::parse(good_bones);
  b["frames"][2]["segments"][1].erase(5);
  std::ofstream(bones) << b.dump();
  EXPECT_EQ(message(), bones.string() + ": frame 2: a segment is not [ax, ay, az, bx, by, bz]");
  b = json::parse(good_bones);
  b["bones"].push_back("elbow>wrist");
  std::ofstream(bones) << b.dump();
  EXPECT_EQ(message(), bones.string() + ": frame 0 does not have one segment for each of the 3 bones");
  std::ofstream(bones) << good_bones;
  EXPECT_EQ(message(), "no error");
  fs::remove_all(f.dir);
}

TEST(RunReport, RunWithoutVtuFramesHasPlotsButNo3DView) {
  StretchConfig c;
  c.resolution = 2;
  c.steps = 2;
  c.write_vtu = false;
  c.out = report_dir("novtu");
  std::ostringstream log;
  (void)run_stretch(c, log);
  const ReportSummary s = write_report(c.out);
  EXPECT_EQ(s.frames, 0);
  const json d = js_payload(c.out / "report" / "data.js", "window.SNH_REPORT = ", ";");
  EXPECT_TRUE(d["mesh"].is_null());
  EXPECT_EQ(d["plots"][0]["x"].size(), 2u);
  fs::remove_all(c.out);
}

TEST(RunReport, OneLineErrors) {
  const fs::path dir = report_dir("errors");
  fs::create_directories(dir);
  auto message = [&](const fs::path& d) {
    try {
      (void)write_report(d);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(dir / "missing"), (dir / "missing").string() + ": does not exist");
  std::ofstream(dir / "a_file") << "x";
  EXPECT_EQ(message(dir / "a_file"), (dir / "a_file").string() + ": is not a directory (the output directory of a run is expected)");
  fs::remove(dir / "a_file");
  EXPECT_EQ(message(dir), dir.string() + ": no stats.json or lab.json here: not the output directory of an snh run");
  std::ofstream(dir / "stats.json") << "{\"steps\": [";
  EXPECT_NE(message(dir).find((dir / "stats.json").string() + ": not valid JSON"), std::string::npos);
  std::ofstream(dir / "stats.json") << "[]";
  EXPECT_EQ(message(dir), (dir / "stats.json").string() + ": not a JSON object");
  std::ofstream(dir / "stats.json") << "{\"frames\": 3}";
  EXPECT_EQ(message(dir), (dir / "stats.json").string() + ": no \"frames\" array");
  std::ofstream(dir / "stats.json") << "{\"command_line\": 5, \"steps\": []}";
  EXPECT_EQ(message(dir).rfind((dir / "stats.json").string() + ": unexpected content ([json.exception.type_error", 0), 0u)
      << message(dir);
  std::ofstream(dir / "stats.json") << "{\"steps\": [], \"all_converged\": true}";
  write_pvd(dir / "frames.pvd", {{0.0, "000.vtu"}});
  const std::string m = message(dir);
  EXPECT_EQ(m.rfind("frame 0: " + (dir / "000.vtu").string() + ": cannot open", 0), 0u) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos);
  fs::remove_all(dir);
}

// The report's own reads (stats.json, lab.json, bones.json, data.js) are checked as every input file is: a
// directory or a FIFO there fails at once with one line (a FIFO blocked the report forever).
TEST(RunReport, ItsJsonInputsAreCheckedBeforeReading) {
  const fs::path dir = report_dir("json_inputs");
  fs::create_directories(dir / "stats.json");
  auto message = [&](const std::function<void()>& f) {
    try {
      f();
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message([&] { (void)write_report(dir); }), (dir / "stats.json").string() + ": is a directory, not a JSON file");
  fs::remove(dir / "stats.json");
  ASSERT_EQ(::mkfifo((dir / "stats.json").c_str(), 0644), 0);
  EXPECT_EQ(message([&] { (void)write_report(dir); }),
            (dir / "stats.json").string() + ": is not a regular file (a FIFO): cannot read a JSON file from it");
  fs::create_directories(dir / "report");
  ASSERT_EQ(::mkfifo((dir / "report" / "data.js").c_str(), 0644), 0);
  EXPECT_EQ(message([&] { (void)read_report_data(dir); }),
            (dir / "report" / "data.js").string() + ": is not a regular file (a FIFO): cannot read a report data file from it");
  fs::remove_all(dir);
}

TEST(LabReport, TablesCurvesAndAReportPerSimulation) {
  LabOptions o;
  o.quick = true;
  o.energies = {"stable_neo_hookean"};
  o.out = report_dir("lab");
  o.command_line = "snh lab --quick";
  const LabReport lab = run_lab(o);
  // One simulation's output broken: only its own page is missing.
  fs::remove(o.out / "rest" / "free_cube" / "stable_neo_hookean" / "001.vtu");
  const ReportSummary s = write_report(o.out);
  EXPECT_EQ(s.kind, "lab");
  const json d = js_payload(o.out / "report" / "data.js", "window.SNH_REPORT = ", ";");
  EXPECT_EQ(d["title"], "snh lab --quick");
  ASSERT_EQ(d["tables"].size(), 7u);  // the six of the text, then every simulation
  EXPECT_EQ(d["tables"][0]["rows"], lab.json["tables"][0]["rows"]);
  EXPECT_EQ(d["tables"][5]["rows"][0][0], "stable_neo_hookean");
  const json& runs = d["tables"][6]["rows"];
  int linked = 0, broken = 0;
  for (const json& r : runs) {
    if (r[3].is_object()) {
      ++linked;
      const std::string href = r[3]["href"];
      EXPECT_TRUE(fs::exists(o.out / href)) << href;
      const std::string html = file_text(o.out / href);
      EXPECT_NE(html.find("src=\"../../../report/snh-report.js\""), std::string::npos) << href;
      EXPECT_FALSE(fs::exists((o.out / href).parent_path() / "report" / "snh-report.js")) << href;
    } else {
      ++broken;
      EXPECT_NE(r[3].get<std::string>().find("no report: frame 1: "), std::string::npos) << r[3];
    }
  }
  EXPECT_EQ(broken, 1);
  EXPECT_EQ(linked, s.runs);
  EXPECT_EQ(static_cast<int>(runs.size()), linked + broken);
  EXPECT_GE(linked, 20);
  // Curves: a volume-over-time plot per case, Poisson, the large stretch and psi(sI).
  std::set<std::string> ids;
  for (const json& p : d["plots"]) {
    ids.insert(p["id"].get<std::string>());
    for (const json& ser : p["series"]) EXPECT_EQ(ser["y"].size(), p["x"].size()) << p["id"];
  }
  for (const char* id : {"rest_free_cube", "inversion_reflected", "degeneracy_point", "poisson", "stretch", "psi_sI"})
    EXPECT_TRUE(ids.count(id)) << id;
  // A render of one of its simulations finds the lab's viewer current and leaves the page as it is (a stale
  // viewer would have the simulation's report written again, with a copy of its own).
  const fs::path sim = o.out / "rest" / "free_cube" / "neo_hookean";
  const std::string page = file_text(sim / "index.html");
  RenderOptions r;
  r.out = sim / "x.png";
  r.browser = "/nonexistent/chromium";
  EXPECT_THROW(render_png(sim, r), ReportError);
  EXPECT_EQ(file_text(sim / "index.html"), page);
  EXPECT_FALSE(fs::exists(sim / "report" / "snh-report.js"));
  fs::remove_all(o.out);
}

TEST(Render, ChecksFrameFieldAndBrowserBeforeStartingIt) {
  StretchRun run = stretch_run(CellType::hex8, "render");
  auto message = [&](RenderOptions o) {
    o.out = run.dir / "x.png";
    try {
      render_png(run.dir, o);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message({.frame = 6}), fmt::format("frame 6 does not exist: {} has frames 0 to 5", run.dir.string()));
  EXPECT_EQ(message({.field = "stress"}), "unknown field 'stress' (this run has: J, psi, displacement)");
  EXPECT_EQ(message({.width = 8}), "the picture size must be from 16 to 8192 pixels each way, got 8x900");
  EXPECT_EQ(message({.browser = "/nonexistent/chromium"}),
            "the browser /nonexistent/chromium cannot be run (from SNH_CHROMIUM or --browser)");
  EXPECT_EQ(message({.view = "side"}), "--view side: expected three-quarter, front, back, left, right or top");
  EXPECT_EQ(message({.fit = "all"}),
            "--fit all: expected frame (the frame shown fills the picture) or animation (every frame would fit)");
  EXPECT_EQ(message({.show = "flesh,skin"}), "--show flesh,skin: expected flesh, lbs, difference or volume, or up to four "
                                             "of them comma-separated (side by side), got 'skin'");
  EXPECT_EQ(message({.show = "flesh,lbs,flesh,lbs,flesh"}), "--show flesh,lbs,flesh,lbs,flesh: at most four side by side");
  EXPECT_EQ(message({.show = "lbs"}), fmt::format("--show: {} is not a flesh run (it has no render surface)", run.dir.string()));
  EXPECT_EQ(message({.focus = "elbow"}), fmt::format("--focus: {} is not a flesh run (it has no render surface)", run.dir.string()));
  EXPECT_EQ(message({.bones = true}), fmt::format("--bones: {} is not a flesh run (it has no render surface)", run.dir.string()));
  EXPECT_EQ(message({.range = "frame"}), fmt::format("--range: {} is not a flesh run (it has no render surface)", run.dir.string()));
  for (const char* bad : {"5:1", "1:1", "0:x", "0:inf", "wide", "3"})
    EXPECT_EQ(message({.range = bad}), fmt::format("--range {}: expected run (the whole run's distances), frame (the frame's own) or "
                                                   "LO:HI in millimetres with LO below HI", bad));
  EXPECT_FALSE(fs::exists(run.dir / "x.png"));
  fs::remove_all(run.dir);
  // A flesh run: --focus names a joint of its bones; --show difference needs a report with the distances.
  const FleshRun f = flesh_run("render_flesh");
  (void)write_report(f.dir);
  auto flesh_message = [&](RenderOptions o) {
    o.out = f.dir / "x.png";
    o.browser = "/nonexistent/chromium";  // every check passed when the browser is the complaint
    try {
      render_png(f.dir, o);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // A report whose viewer another build wrote is written again before the browser starts.
  std::ofstream(f.dir / "report" / "snh-report.js") << "/* an older viewer */\n";
  EXPECT_EQ(flesh_message({}), "the browser /nonexistent/chromium cannot be run (from SNH_CHROMIUM or --browser)");
  EXPECT_EQ(file_text(f.dir / "report" / "snh-report.js"), std::string(report_bundle()));
  EXPECT_EQ(flesh_message({.focus = "knee"}), "--focus knee: no joint of that name (the run's joints: shoulder, elbow, wrist)");
  EXPECT_EQ(flesh_message({.show = "difference", .focus = "elbow"}), "the browser /nonexistent/chromium cannot be run (from SNH_CHROMIUM or --browser)");
  json old = read_report_data(f.dir);
  old["render"].erase("distance");
  std::ofstream(f.dir / "report" / "data.js") << "window.SNH_REPORT = " << old.dump() << ";\n";
  EXPECT_EQ(flesh_message({.show = "flesh,difference"}),
            fmt::format("--show difference: the report of {} has no flesh–LBS distances (an older snh wrote it): run snh report {} first",
                        f.dir.string(), f.dir.string()));
  fs::remove_all(f.dir);
}

// --compare: a run with another run's skin in place of the skinned one, its report measuring the distance of
// the first run's skin from the second's (brute force here), both named by their directories; runs of other
// skins or frame counts, and runs that are not flesh runs, are refused in one line.
TEST(Render, ComparesTwoRunsOfOneSkin) {
  const FleshRun a = flesh_run("cmp_a");
  FleshRun b = flesh_run("cmp_b");
  for (int i = 0; i < b.frames; ++i) {  // b's flesh grows twice as fast, and moves up
    b.flesh[i] = (a.flesh[0] * (1.0 + 0.2 * i)).colwise() + Eigen::Vector3d(0.0, 0.0, 0.01 * i);
    write_obj(b.dir / "surface" / fmt::format("{:03d}.obj", i), b.flesh[i], b.triangles);
  }
  const fs::path into = report_dir("cmp_pair");
  fs::create_directories(into);
  const fs::path run = comparison_run(a.dir, b.dir, into);
  const json d = read_report_data(run);
  EXPECT_EQ(d["render"]["labels"]["flesh"], a.dir.filename().string());
  EXPECT_EQ(d["render"]["labels"]["lbs"], b.dir.filename().string());
  EXPECT_EQ(d["title"], fmt::format("{} against {}", a.dir.filename().string(), b.dir.filename().string()));
  for (int i = 0; i < a.frames; ++i) {
    const json fd = js_payload(run / d["mesh"]["frames"][i]["src"].get<std::string>(), fmt::format("snhReportFrame({}, ", i), ");");
    const auto dist = decode<float>(fd["render"]["distance"]);
    ASSERT_EQ(dist.size(), 6u);
    for (int v = 0; v < 6; ++v) {
      const double expected = nearest_mm(a.flesh[i].col(v), b.flesh[i], b.triangles);
      EXPECT_NEAR(std::abs(dist[v]), expected, 1e-6 * (1.0 + expected)) << "frame " << i << " vertex " << v;
      if (i > 1) {
        EXPECT_LT(dist[v], 0.0f) << "a's skin lies inside b's: frame " << i << " vertex " << v;
      }
    }
  }
  // The runs' own directories are as they were: the pair links their files.
  EXPECT_TRUE(fs::is_symlink(run / "lbs"));
  EXPECT_EQ(fs::read_symlink(run / "lbs"), fs::absolute(b.dir / "surface"));
  EXPECT_TRUE(fs::is_directory(a.dir / "lbs") && !fs::is_symlink(a.dir / "lbs"));

  auto refused = [&](const fs::path& x, const fs::path& y) {
    const fs::path to = report_dir("cmp_refused");
    fs::remove_all(to);
    fs::create_directories(to);
    try {
      (void)comparison_run(x, y, to);
    } catch (const ReportError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // Another skin: one triangle fewer.
  FleshRun c = flesh_run("cmp_c");
  write_obj(c.dir / "surface" / "000.obj", c.flesh[0], c.triangles.leftCols(7));
  EXPECT_EQ(refused(a.dir, c.dir), fmt::format("--compare: the skin of {} has 6 vertices and 7 triangles, that of {} 6 and 8: runs of one "
                                               "model are compared", c.dir.string(), a.dir.string()));
  // Fewer frames.
  FleshRun e = flesh_run("cmp_e");
  std::string pvd = file_text(e.dir / "frames.pvd");
  pvd.erase(pvd.rfind("<DataSet"), pvd.find('\n', pvd.rfind("<DataSet")) - pvd.rfind("<DataSet") + 1);
  std::ofstream(e.dir / "frames.pvd") << pvd;
  EXPECT_EQ(refused(a.dir, e.dir), fmt::format("--compare: {} has 4 frames, {} has 5: runs of one animation at one frame rate are compared",
                                               e.dir.string(), a.dir.string()));
  StretchRun plain = stretch_run(CellType::hex8, "cmp_plain");
  EXPECT_EQ(refused(a.dir, plain.dir), fmt::format("--compare: {} is not a flesh run (it has no surface/000.obj or frames.pvd)", plain.dir.string()));
  EXPECT_EQ(refused(a.dir, a.dir / "missing"), fmt::format("--compare: {}: not a run's directory", (a.dir / "missing").string()));
  for (const fs::path& p : {a.dir, b.dir, c.dir, e.dir, plain.dir, into, report_dir("cmp_refused")}) fs::remove_all(p);
}

TEST(Render, ABrowserThatNeverAnswersIsKilledAtTheTimeoutAndLeavesNothing) {
  StretchRun run = stretch_run(CellType::hex8, "render_hang");
  const fs::path tmp = run.dir / "tmp", browser = run.dir / "silent-browser", pid_file = run.dir / "browser.pid";
  fs::create_directories(tmp);
  std::ofstream(browser) << "#!/bin/sh\necho $$ > " << pid_file.string() << "\nexec sleep 60\n";
  fs::permissions(browser, fs::perms::owner_all);
  const char* tmpdir = std::getenv("TMPDIR");
  const std::string saved = tmpdir ? tmpdir : "";
  ::setenv("TMPDIR", tmp.c_str(), 1);  // the render's temporary directory goes here
  RenderOptions o;
  o.out = run.dir / "x.png";
  o.browser = browser.string();
  o.timeout_seconds = 1;
  std::string message = "no error";
  try {
    render_png(run.dir, o);
  } catch (const BrowserError& e) {
    message = e.what();
  }
  tmpdir ? ::setenv("TMPDIR", saved.c_str(), 1) : ::unsetenv("TMPDIR");
  EXPECT_EQ(message, fmt::format("the browser {} did not finish within 1 s (waiting for Target.createTarget)", browser.string()));
  const pid_t pid = std::stoi(file_text(pid_file));
  EXPECT_NE(::kill(pid, 0), 0) << "the browser (process " << pid << ") is still running";
  EXPECT_TRUE(fs::is_empty(tmp)) << "the render's temporary directory was left";
  EXPECT_FALSE(fs::exists(o.out));
  fs::remove_all(run.dir);
}

TEST(Render, AStopRequestedBeforeTheBrowserStartsEndsTheRender) {
  StretchRun run = stretch_run(CellType::tet4, "render_stop");
  RenderOptions o;
  o.out = run.dir / "x.png";
  o.browser = "/bin/true";
  request_stop(SIGTERM);
  int signal = 0;
  try {
    render_png(run.dir, o);
  } catch (const BrowserInterrupted& e) {
    signal = e.signal;
  }
  request_stop(0);
  EXPECT_EQ(signal, SIGTERM);
  EXPECT_FALSE(fs::exists(o.out));
  fs::remove_all(run.dir);
}

TEST(Render, PngSizeReadsTheHeader) {
  const fs::path dir = report_dir("png");
  fs::create_directories(dir);
  const unsigned char png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                               0, 0, 0x04, 0xB0, 0, 0, 0x03, 0x84, 8, 6, 0, 0, 0};
  std::ofstream(dir / "a.png", std::ios::binary).write(reinterpret_cast<const char*>(png), sizeof png);
  EXPECT_EQ(png_size(dir / "a.png"), (std::pair<int, int>{1200, 900}));
  std::ofstream(dir / "b.png") << "not a png at all, really";
  EXPECT_EQ(png_size(dir / "b.png"), (std::pair<int, int>{0, 0}));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace snh
