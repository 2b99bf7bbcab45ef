// Tissues and muscles in scenes (setup/muscles.hpp): every key checked, a region's material only in its cells,
// the harmonic fibre field against its exact solution, a free muscle's closed form and a pinned muscle's force
// through the whole scene path, activation by keys and by a line of action, bone tissues and model meshes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "limb_model.hpp"
#include "scene_error.hpp"
#include "snh/embed/winding_number.hpp"
#include "snh/mesh/box.hpp"
#include "snh/setup/muscles.hpp"
#include "snh/setup/scene_build.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::error_of;

/// A quasi-static bar [0, 4] × [0, 1]² of 8 × 2 × 2 hexes (cells 0.5 wide), E = 1000, ν = 0.45.
json bar() {
  return json::parse(R"({
    "mesh": {"box": {"min": [0, 0, 0], "max": [4, 1, 1], "res": 8}},
    "material": {"youngs": 1000, "poisson": 0.45},
    "integrator": "quasi_static", "end_time": 1, "frames": 4,
    "output": {"dir": "unused"}})");
}

json belly() {
  return json::parse(R"({"name": "belly", "region": {"min": [-1, -1, -1], "max": [5, 2, 2]}, "fibre": [1, 0, 0], "contraction": 0.3,
                         "activation": [{"time": 0, "value": 0}, {"time": 1, "value": 1}]})");
}

TEST(MuscleScene, EveryKeyIsCheckedAndNamed) {
  const auto with = [](const json& muscle, const std::string& list = "muscles") {
    json j = bar();
    j[list] = json::array({muscle});
    return error_of(j);
  };
  const auto changed = [](const json& patch) {
    json m = belly();
    for (auto it = patch.begin(); it != patch.end(); ++it)
      if (it->is_null()) m.erase(it.key());
      else m[it.key()] = *it;
    return m;
  };
  EXPECT_EQ(with(belly()), "");
  EXPECT_NE(with(json::object()).find("muscles[0]: needs name"), std::string::npos);
  EXPECT_NE(with(changed({{"region", nullptr}})).find("muscles[0]: needs region"), std::string::npos);
  EXPECT_NE(with(changed({{"fibre", nullptr}})).find("muscles[0]: needs fibre"), std::string::npos);
  EXPECT_NE(with(changed({{"fibre", {0, 0, 0}}})).find("muscles[0].fibre: a fibre direction must not be zero"), std::string::npos);
  EXPECT_NE(with(changed({{"contraction", 1}})).find("muscles[0].contraction: must be below 1"), std::string::npos);
  EXPECT_NE(with(changed({{"contraction", -0.1}})).find("muscles[0].contraction: must be >= 0"), std::string::npos);
  EXPECT_NE(with(changed({{"colour", "red"}})).find("muscles[0].colour: unknown key"), std::string::npos);
  EXPECT_NE(with(changed({{"fibre_model", "hill"}})).find("muscles[0].fibre_model: expected one of signed_arap, quadratic"),
            std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"min", {0, 0, 0}}}}})).find("muscles[0].region: min and max go together"), std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"min", {0, 0, 0}}, {"max", {1, 0, 1}}}}})).find("min must be below max"), std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"mesh", "m.obj"}, {"model_mesh", "a"}}}})).find("one of them"), std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"model_mesh", "a"}}}})).find("only in a flesh scene"), std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"min", {10, 10, 10}}, {"max", {11, 11, 11}}}}})).find("muscles[0] \"belly\": the region holds no cell"),
            std::string::npos);
  EXPECT_NE(with(changed({{"region", {{"mesh", "/nonexistent/m.obj"}}}})).find("muscles[0] \"belly\".region.mesh: "), std::string::npos);
  EXPECT_NE(with(changed({{"activation", {{{"time", 0}, {"value", 1.5}}}}})).find("muscles[0].activation[0].value: must be from 0 to 1"),
            std::string::npos);
  EXPECT_NE(with(changed({{"activation", {{{"time", 1}, {"value", 0}}, {{"time", 1}, {"value", 1}}}}})).find("key times must increase"),
            std::string::npos);
  EXPECT_NE(with(changed({{"activation", {{"line_of_action", {{"from", "a"}, {"to", "b"}}}}}})).find("needs a flesh scene's joints"),
            std::string::npos);
  EXPECT_NE(with(changed({{"fibre", {{"origin", "shoulder"}, {"insertion", {1, 0, 0}}}}})).find("only in a flesh scene"), std::string::npos);
  EXPECT_NE(with(changed({{"fibre", {{"origin", {1, 0.5, 0.5}}, {"insertion", {1, 0.5, 0.5}}}}})).find("the same point"),
            std::string::npos);
  // Tissues take no fibres; a bone needs a flesh's joints.
  EXPECT_NE(with({{"name", "fat"}, {"region", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}}, {"fibre", {1, 0, 0}}}, "tissues").find("tissues[0].fibre: unknown key"),
            std::string::npos);
  EXPECT_NE(with({{"name", "b"}, {"region", {{"min", {0, 0, 0}}, {"max", {1, 1, 1}}}}, {"bone", "x"}}, "tissues").find("needs a flesh scene"),
            std::string::npos);
  json two = bar();
  two["muscles"] = json::array({belly(), belly()});
  EXPECT_NE(error_of(two).find("muscles[1].name: the name \"belly\" is given twice"), std::string::npos);
  // A later region that takes every cell of an earlier one leaves it empty.
  two["muscles"][1]["name"] = "whole";
  EXPECT_NE(error_of(two).find("muscles[0] \"belly\": the region holds no cell's centre (or later entries took all its cells)"),
            std::string::npos);
}

TEST(MuscleScene, ARegionsMaterialIsUsedOnlyInItsCells) {
  json j = bar();
  j["tissues"] = json::array({{{"name", "stiff"}, {"region", {{"min", {2, -1, -1}}, {"max", {5, 2, 2}}}}, {"material", {{"mu", 50}, {"lambda", 500}}}}});
  const BuiltScene b = build_scene(parse_scene(j, "s.json"));
  ASSERT_TRUE(b.muscles);
  const Simulation sim(simulation_setup(b));
  const VolumeMesh& mesh = sim.mesh();
  int stiff = 0;
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    double centre = 0.0;
    for (Eigen::Index k = 0; k < 8; ++k) centre += mesh.vertices(0, mesh.cells(k, c)) / 8.0;
    const double mu = std::visit([](const auto& m) { return m.params().mu; }, sim.elastic().material(c));
    if (centre > 2.0) {
      EXPECT_EQ(mu, 50.0) << "cell " << c;
      ++stiff;
    } else {
      EXPECT_NEAR(mu, 1000.0 / 2.9, 1e-9) << "cell " << c;
    }
    EXPECT_EQ(sim.elastic().fibre(c), nullptr);
  }
  EXPECT_EQ(stiff, 256) << "half of the 8³ cells";
}

TEST(MuscleScene, ARegionOfAMeshFilesCellTags) {
  // Two hexes along x, MEDIT references 1 and 2; the tissue takes the cells tagged 2.
  const fs::path dir = fs::temp_directory_path() / ("snh-test-tags-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::string medit = "MeshVersionFormatted 2\nDimension 3\nVertices 12\n";
  for (int v = 0; v < 12; ++v) medit += fmt::format("{} {} {} 0\n", v % 3, (v / 3) % 2, v / 6);
  medit += "Hexahedra 2\n";
  for (int c = 0; c < 2; ++c) {
    for (int a : {0, 1, 3, 2, 4, 5, 7, 6}) medit += fmt::format("{} ", c + (a & 1) + 3 * ((a >> 1) & 1) + 6 * (a >> 2) + 1);
    medit += fmt::format("{}\n", c + 1);
  }
  std::ofstream(dir / "two.mesh") << medit << "End\n";
  json j = {{"mesh", {{"file", (dir / "two.mesh").string()}}}, {"material", {{"mu", 1}, {"lambda", 10}}},
            {"tissues", {{{"name", "second"}, {"region", {{"tags", {2}}}}, {"material", {{"mu", 50}, {"lambda", 500}}}}}}};
  const BuiltScene b = build_scene(parse_scene(j, "s.json"));
  EXPECT_EQ(b.muscles->region_of_cell, (std::vector<int>{-1, 0}));
  EXPECT_EQ(b.muscles->material_of_cell, (std::vector<int>{0, 1}));
  j["tissues"][0]["region"]["tags"] = {5, 6};
  EXPECT_NE(error_of(j).find("tissues[0] \"second\".region.tags: no cell has these tags (the mesh's cells have: 1, 2)"), std::string::npos)
      << error_of(j);
  j["tissues"][0]["region"]["tags"] = {1.5};
  EXPECT_NE(error_of(j).find("tissues[0].region.tags: expected integer tags, got 1.5"), std::string::npos) << error_of(j);
  json box = bar();
  box["tissues"] = {{{"name", "t"}, {"region", {{"tags", {1}}}}}};
  EXPECT_NE(error_of(box).find("region.tags: the mesh has no cell tags"), std::string::npos) << error_of(box);
  fs::remove_all(dir);
}

TEST(MuscleScene, FibresFromAFileOfOnePerCell) {
  const fs::path dir = fs::temp_directory_path() / ("snh-test-fibre-file-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream out(dir / "f.txt");
  out << "# one direction per cell\n";
  for (int c = 0; c < 512; ++c) out << (c % 2 ? "0 0 2" : "1 1 0") << (c == 7 ? "  # a comment\n\n" : "\n");
  out.close();
  json j = bar();
  j["muscles"] = json::array({belly()});
  j["muscles"][0]["fibre"] = {{"file", (dir / "f.txt").string()}};
  j["muscles"][0]["region"] = {{"min", {2, -1, -1}}, {"max", {5, 2, 2}}};
  const BuiltScene b = build_scene(parse_scene(j, "s.json"));
  const Simulation sim(simulation_setup(b));
  int muscle = 0;
  for (Eigen::Index c = 0; c < sim.mesh().cell_count(); ++c)
    if (const CellFibre* f = sim.elastic().fibre(c)) {
      ++muscle;
      const Vec3 want = c % 2 ? Vec3::UnitZ() : Vec3(1, 1, 0).normalized();
      EXPECT_LT((f->direction - want).norm(), 1e-15) << "cell " << c;
    }
  EXPECT_EQ(muscle, 256);
  std::ofstream(dir / "short.txt") << "1 0 0\n";
  j["muscles"][0]["fibre"]["file"] = (dir / "short.txt").string();
  EXPECT_NE(error_of(j).find("short.txt: 1 directions for the volume's 512 cells"), std::string::npos) << error_of(j);
  std::ofstream(dir / "bad.txt") << "1 0 0\n1 0 x\n";
  j["muscles"][0]["fibre"]["file"] = (dir / "bad.txt").string();
  EXPECT_NE(error_of(j).find("bad.txt:2: expected three finite numbers (a fibre direction), got \"1 0 x\""), std::string::npos) << error_of(j);
  std::ofstream(dir / "zero.txt") << "0 0 0\n";
  j["muscles"][0]["fibre"]["file"] = (dir / "zero.txt").string();
  EXPECT_NE(error_of(j).find("zero.txt:1: a fibre direction must not be zero"), std::string::npos) << error_of(j);
  j["muscles"][0]["fibre"]["file"] = dir.string();
  EXPECT_NE(error_of(j).find("fibre.file: " + dir.string() + ": is a directory"), std::string::npos) << error_of(j);
  j["muscles"][0]["fibre"] = {{"file", "f.txt"}, {"origin", {0, 0, 0}}};
  EXPECT_NE(error_of(j).find("give a file, or an origin and an insertion: not both"), std::string::npos) << error_of(j);
  fs::remove_all(dir);
}

/// The x-component of the elastic force (−∂E/∂x) on the vertices of the face x = 0 (what the pins there hold).
double held_force(const ElasticTerm& term, const Eigen::VectorXd& x) {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  (void)term.evaluate(x, &g, nullptr, PsdProjection::none);
  double f = 0.0;
  for (Eigen::Index v = 0; v < term.mesh().vertex_count(); ++v)
    if (term.mesh().vertices(0, v) == 0.0) f -= g[3 * v];
  return f;
}

TEST(MuscleScene, APinnedMusclePullsHarderWithMoreActivation) {
  json j = bar();
  j["pins"] = json::array({{{"region", {{"min", {-0.1, -1, -1}}, {"max", {0.1, 2, 2}}}}}, {{"region", {{"min", {3.9, -1, -1}}, {"max", {4.1, 2, 2}}}}}});
  j["muscles"] = json::array({belly()});
  const BuiltScene b = build_scene(parse_scene(j, "s.json"));
  Simulation sim(simulation_setup(b));
  EXPECT_NEAR(held_force(sim.elastic(), sim.x()), 0.0, 1e-12) << "no activation at t = 0: the rest state";
  double last = 0.0;
  std::vector<double> force;
  for (int frame = 1; frame <= 4; ++frame) {
    const StepReport r = sim.advance(0.25 * (frame - 1), 0.25, 1);
    ASSERT_TRUE(r.converged) << r.failure;
    const double f = held_force(sim.elastic(), sim.x());  // the muscle pulls the face towards +x
    EXPECT_GT(f, last) << "frame " << frame;
    last = f;
    force.push_back(f);
  }
  // The same state of a term whose active strain is set by hand gives the same force: the scene's activation
  // (keys 0 → 1 over t ∈ [0, 1]) reached the cells as α = γ a = 0.3 at t = 1.
  ElasticTerm term(sim.mesh(), sim.elastic().materials()[0]);
  std::vector<CellFibre> one{sim.elastic().fibres()[0]};
  term.set_fibres(std::vector<int>(static_cast<std::size_t>(sim.mesh().cell_count()), 0), one);
  term.set_active_strain(0, ActiveStrain::along(Vec3::UnitX(), 0.3));
  const double by_hand = held_force(term, sim.x());
  EXPECT_NEAR(by_hand, force.back(), 1e-12 * std::abs(by_hand));
  // Small activations: the force grows about linearly (a quarter of the way, 0.075 of strain, is still mild).
  EXPECT_NEAR(force[1] / force[0], 2.0, 0.25);
}

TEST(MuscleScene, AFreeMuscleTakesItsActiveShape) {
  // Held only against rigid motion: the face x = 0 on x, one vertex of it on y and z, another on z.
  json j = bar();
  j["pins"] = json::array({{{"region", {{"min", {-0.1, -1, -1}}, {"max", {0.1, 2, 2}}}}, {"axes", "x"}},
                           {{"indices", {0}}, {"axes", "yz"}},
                           {{"region", {{"min", {-0.1, 0.9, -0.1}}, {"max", {0.1, 1.1, 0.1}}}}, {"axes", "z"}}});
  j["muscles"] = json::array({belly()});
  j["muscles"][0]["activation"] = json::array({{{"time", 0}, {"value", 0}}, {{"time", 1}, {"value", 0.5}}});
  j["solver"] = {{"tolerance", 1e-10}};
  const BuiltScene b = build_scene(parse_scene(j, "s.json"));
  Simulation sim(simulation_setup(b));
  ASSERT_TRUE(sim.advance(0.0, 0.5, 2).converged);
  // α = 0.3 · 0.5: along x 1 − α, across (1 − α)^(−1/2), about the held vertex 0 (at the origin).
  const double alpha = 0.15, along = 1.0 - alpha, across = 1.0 / std::sqrt(along);
  const Eigen::Map<const Eigen::Matrix3Xd> x(sim.x().data(), 3, sim.mesh().vertex_count());
  double worst = 0.0, volume = 0.0;
  for (Eigen::Index v = 0; v < x.cols(); ++v) {
    const Eigen::Vector3d X = sim.mesh().vertices.col(v);
    worst = std::max(worst, (x.col(v) - Eigen::Vector3d(along * X[0], across * X[1], across * X[2])).norm());
  }
  EXPECT_LT(worst, 1e-8);
  volume = along * across * across;
  EXPECT_NEAR(volume, 1.0, 1e-12);
}

/// A quarter annulus, r ∈ [1, 2], θ ∈ [0, π/2], z ∈ [0, 0.5], of nr × nt × 1 hexes.
VolumeMesh quarter_annulus(int nr, int nt) {
  VolumeMesh m;
  m.type = CellType::hex8;
  const auto id = [&](int i, int j, int k) { return (k * (nt + 1) + j) * (nr + 1) + i; };
  m.vertices.resize(3, (nr + 1) * (nt + 1) * 2);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j <= nt; ++j)
      for (int i = 0; i <= nr; ++i) {
        const double r = 1.0 + double(i) / nr, t = 0.5 * std::numbers::pi * j / nt;
        m.vertices.col(id(i, j, k)) = Eigen::Vector3d(r * std::cos(t), r * std::sin(t), 0.5 * k);
      }
  m.cells.resize(8, nr * nt);
  for (int j = 0; j < nt; ++j)
    for (int i = 0; i < nr; ++i)  // corner order: c1 = c0 + r, c2 = c0 + θ, c4.. = c0.. + z (positive volume)
      m.cells.col(j * nr + i) << id(i, j, 0), id(i + 1, j, 0), id(i, j + 1, 0), id(i + 1, j + 1, 0), id(i, j, 1), id(i + 1, j, 1),
          id(i, j + 1, 1), id(i + 1, j + 1, 1);
  return m;
}

TEST(HarmonicFibres, RunAroundABentRegionAsItsExactField) {
  // u = 2θ/π is harmonic, 0 on the face θ = 0, 1 on θ = π/2, with no flux through the others: the fibres are
  // the tangents (−sin θ, cos θ, 0).
  const VolumeMesh m = quarter_annulus(4, 24);
  std::vector<int> cells(static_cast<std::size_t>(m.cell_count())), origin, insertion;
  for (int c = 0; c < m.cell_count(); ++c) cells[static_cast<std::size_t>(c)] = c;
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v) {
    if (std::abs(m.vertices(1, v)) < 1e-12) origin.push_back(static_cast<int>(v));
    if (std::abs(m.vertices(0, v)) < 1e-12) insertion.push_back(static_cast<int>(v));
  }
  const std::vector<Eigen::Vector3d> f = harmonic_fibres(m, cells, origin, insertion, Eigen::Vector3d::UnitX());
  double worst = 0.0;
  for (Eigen::Index c = 0; c < m.cell_count(); ++c) {
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int k = 0; k < 8; ++k) centre += m.vertices.col(m.cells(k, c)) / 8.0;
    const double t = std::atan2(centre[1], centre[0]);
    worst = std::max(worst, std::acos(std::min(1.0, f[static_cast<std::size_t>(c)].dot(Eigen::Vector3d(-std::sin(t), std::cos(t), 0.0)))));
  }
  EXPECT_LT(worst, 0.01) << "radians";
  // A straight box gives its axis; the ends must differ; points pick the vertices near them.
  const VolumeMesh box = box_hexes(3);
  std::vector<int> all(27);
  for (int c = 0; c < 27; ++c) all[static_cast<std::size_t>(c)] = c;
  const std::vector<int> lo = attachment_vertices(box, all, Eigen::Vector3d(0, 0, -1000), 0.01),
                         hi = attachment_vertices(box, all, Eigen::Vector3d(0, 0, 1000), 0.01);
  EXPECT_EQ(lo.size(), 16u) << "the face z = -1";
  for (const Eigen::Vector3d& a : harmonic_fibres(box, all, lo, hi, Eigen::Vector3d::UnitX())) EXPECT_LT((a - Eigen::Vector3d::UnitZ()).norm(), 1e-9);
  EXPECT_THROW((void)harmonic_fibres(box, all, lo, lo, Eigen::Vector3d::UnitX()), std::invalid_argument);
  EXPECT_THROW((void)harmonic_fibres(box, all, {}, hi, Eigen::Vector3d::UnitX()), std::invalid_argument);
}

/// A closed UV sphere of radius r about c (n rings, m segments), outward.
void uv_sphere(double r, const Eigen::Vector3d& c, int n, int m, Eigen::Matrix3Xd& V, Eigen::Matrix3Xi& F) {
  V.resize(3, 2 + (n - 1) * m);
  V.col(0) = c + Eigen::Vector3d(0, 0, r);
  for (int i = 1; i < n; ++i)
    for (int k = 0; k < m; ++k) {
      const double t = M_PI * i / n, a = 2 * M_PI * k / m;
      V.col(1 + (i - 1) * m + k) = c + r * Eigen::Vector3d(std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t));
    }
  V.col(V.cols() - 1) = c - Eigen::Vector3d(0, 0, r);
  const auto at = [&](int i, int k) { return 1 + (i - 1) * m + (k % m); };
  std::vector<Eigen::Vector3i> tris;
  for (int k = 0; k < m; ++k) {
    tris.emplace_back(0, at(1, k), at(1, k + 1));
    tris.emplace_back(int(V.cols()) - 1, at(n - 1, k + 1), at(n - 1, k));
  }
  for (int i = 1; i < n - 1; ++i)
    for (int k = 0; k < m; ++k) {
      tris.emplace_back(at(i, k), at(i + 1, k), at(i + 1, k + 1));
      tris.emplace_back(at(i, k), at(i + 1, k + 1), at(i, k + 1));
    }
  F.resize(3, static_cast<Eigen::Index>(tris.size()));
  for (std::size_t t = 0; t < tris.size(); ++t) F.col(static_cast<Eigen::Index>(t)) = tris[t];
}

TEST(CellsInside, TheGroupedWindingNumbersAreEachCellsOwn) {
  // Two closed spheres (one inside out) against hexes and tets, and an open one (a cap removed): the cells
  // found are those whose own winding number has magnitude ½ or more.
  Eigen::Matrix3Xd A, B;
  Eigen::Matrix3Xi FA, FB;
  uv_sphere(0.55, Eigen::Vector3d(0.1, -0.05, 0.02), 16, 24, A, FA);
  uv_sphere(0.3, Eigen::Vector3d(-0.5, 0.4, 0.3), 10, 12, B, FB);
  for (Eigen::Index t = 0; t < FB.cols(); ++t) std::swap(FB(1, t), FB(2, t));  // inward
  Eigen::Matrix3Xd V(3, A.cols() + B.cols());
  V << A, B;
  Eigen::Matrix3Xi F(3, FA.cols() + FB.cols());
  F << FA, (FB.array() + int(A.cols())).matrix();
  const Eigen::Matrix3Xi open = F.rightCols(F.cols() - 24);  // the first sphere's top cap gone
  for (const VolumeMesh& mesh : {box_hexes(14), box_tets(9)})
    for (const Eigen::Matrix3Xi* tris : {static_cast<const Eigen::Matrix3Xi*>(&F), &open}) {
      std::vector<int> brute;
      for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
        Eigen::Vector3d centre = Eigen::Vector3d::Zero();
        for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) centre += mesh.vertices.col(mesh.cells(k, c)) / double(mesh.cells.rows());
        if (std::abs(winding_number(V, *tris, centre)) >= 0.5) brute.push_back(static_cast<int>(c));
      }
      EXPECT_GT(brute.size(), 20u);
      EXPECT_EQ(cells_inside(mesh, V, *tris), brute) << (tris == &F ? "closed" : "open") << ", " << mesh.cell_count() << " cells";
    }
}

class MuscleLimb : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("snh-test-muscles-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    test::write_limb_gltf(dir_ / "limb.gltf");
    test::write_limb_gltf(dir_ / "pair.gltf", {.beside_overlap = 0.1});
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static json scene(const std::string& model = "limb.gltf") {
    return {{"flesh", {{"model", (dir_ / model).string()}, {"resolution", 10}}}, {"frames", 2}, {"output", {{"dir", (dir_ / "out").string()}}}};
  }
  static inline fs::path dir_;
};

TEST_F(MuscleLimb, ALineOfActionFollowsTheJoints) {
  // From a point on the upper arm to one on the forearm: the elbow's 90° bend about z (over 1 s) brings the
  // forearm's point (0.5, 0.2) from the elbow to (−0.2, 0.5), that is to (0.8, 0.5), from (0.5, 0.2) at rest.
  json j = scene();
  j["muscles"] = json::array({{{"name", "flexor"}, {"region", {{"min", {0.2, -1, -1}}, {"max", {0.8, 1, 1}}}}, {"fibre", {1, 0, 0}},
                               {"activation", {{"line_of_action", {{"from", {{"joint", "shoulder"}, {"point", {0.5, 0.2, 0}}}},
                                                                   {"to", {{"joint", "elbow"}, {"point", {1.5, 0.2, 0}}}}, {"gain", 1.5}}}}}}});
  const BuiltScene b = build_scene(parse_scene(j, dir_ / "s.json"));
  ASSERT_TRUE(b.muscles);
  const double rest = 1.0, bent = std::hypot(0.3, 0.3);
  EXPECT_NEAR(b.muscles->activation(0.0)[0], 0.0, 1e-7);
  EXPECT_NEAR(b.muscles->activation(1.0)[0], 1.5 * (1.0 - bent / rest), 1e-6);
  const double half = std::hypot(1.0 + 0.5 * std::cos(M_PI / 4) - 0.2 * std::sin(M_PI / 4) - 0.5,
                                 0.5 * std::sin(M_PI / 4) + 0.2 * std::cos(M_PI / 4) - 0.2);
  EXPECT_NEAR(b.muscles->activation(0.5)[0], 1.5 * (1.0 - half / rest), 1e-6);
  // The clamp: a gain of 10 saturates at max.
  j["muscles"][0]["activation"]["line_of_action"]["gain"] = 10;
  j["muscles"][0]["activation"]["line_of_action"]["max"] = 0.8;
  EXPECT_NEAR(build_scene(parse_scene(j, dir_ / "s.json")).muscles->activation(1.0)[0], 0.8, 0.0);
  // A joint the model lacks is named with the joints it has.
  j["muscles"][0]["activation"]["line_of_action"]["to"] = "knee";
  EXPECT_NE(error_of(j).find("muscles[0] \"flexor\": activation.line_of_action.to: the model " + (dir_ / "limb.gltf").string() +
                            " has no joint \"knee\" (its joints: shoulder, elbow, tip)"),
            std::string::npos)
      << error_of(j);
  // The run: the muscle's line says its activation, muscles.json holds its fibres and activation per frame.
  j["muscles"][0]["activation"]["line_of_action"]["to"] = json{{"joint", "elbow"}, {"point", {1.5, 0.2, 0}}};
  std::ostringstream log;
  const SceneResult r = run_scene(parse_scene(j, dir_ / "s.json"), log);
  EXPECT_TRUE(r.all_converged) << log.str();
  EXPECT_NE(log.str().find("muscle flexor: "), std::string::npos);
  EXPECT_NE(log.str().find(", activation flexor 0.800"), std::string::npos) << log.str();
  std::ifstream in(dir_ / "out" / "muscles.json");
  const json m = json::parse(in);
  ASSERT_EQ(m["regions"].size(), 1u);
  EXPECT_EQ(m["regions"][0]["activation"].size(), 3u);
  EXPECT_EQ(m["regions"][0]["fibre_directions"].size(), m["regions"][0]["cells"].size());
  // A run that stops at its first frame (one Newton iteration cannot reach the bent elbow) keeps muscles.json,
  // every frame's activation in it.
  json stop = j;
  stop["solver"] = {{"max_iterations", 1}};
  stop["output"]["dir"] = (dir_ / "stop").string();
  std::ostringstream stopped;
  EXPECT_FALSE(run_scene(parse_scene(stop, dir_ / "s.json"), stopped).all_converged) << stopped.str();
  std::ifstream kept(dir_ / "stop" / "muscles.json");
  EXPECT_EQ(json::parse(kept)["regions"][0]["activation"].size(), 3u);
  // A run without muscles into the same directory leaves no muscles.json of the last one.
  std::ostringstream again;
  EXPECT_TRUE(run_scene(parse_scene(scene(), dir_ / "s.json"), again).all_converged) << again.str();
  EXPECT_FALSE(fs::exists(dir_ / "out" / "muscles.json"));
}

TEST_F(MuscleLimb, ModelMeshesAndBoneTissues) {
  // The still limb sunk into the first is a mesh of its own: its region is the cells whose centre it holds.
  json j = scene("pair.gltf");
  j["tissues"] = json::array({{{"name", "still"}, {"region", {{"model_mesh", "limb_far"}}}, {"material", {{"mu", 1e4}, {"lambda", 1e5}}}}});
  const BuiltScene b = build_scene(parse_scene(j, dir_ / "s.json"));
  const VolumeMesh& mesh = b.body->mesh;
  int inside = 0;
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    if (b.muscles->region_of_cell[static_cast<std::size_t>(c)] != 0) continue;
    ++inside;
    double z = 0.0;
    for (Eigen::Index k = 0; k < 8; ++k) z += mesh.vertices(2, mesh.cells(k, c)) / 8.0;
    EXPECT_GT(z, 0.5 - 0.3 - 1e-9) << "cell " << c << " is outside the still limb (axis z = 0.5, radius 0.3)";
  }
  EXPECT_GT(inside, 10);
  j["tissues"][0]["region"]["model_mesh"] = "nothing";
  EXPECT_NE(error_of(j).find("no mesh named \"nothing\" in the model (its meshes: limb, limb_far)"), std::string::npos) << error_of(j);
  // A bone tissue around the tip follows the elbow rigidly.
  json k = scene();
  k["tissues"] = json::array({{{"name", "cap"}, {"region", {{"min", {1.8, -1, -1}}, {"max", {3, 1, 1}}}}, {"bone", "elbow"}}});
  const BuiltScene c = build_scene(parse_scene(k, dir_ / "s.json"));
  ASSERT_EQ(c.muscles->bones.size(), 1u);
  const KinematicSet& set = c.muscles->bones[0];
  Eigen::Matrix3Xd at(3, static_cast<Eigen::Index>(set.vertices.size()));
  set.provider->targets(1.0, at);
  for (std::size_t i = 0; i < set.vertices.size(); ++i) {
    const Eigen::Vector3d X = c.body->mesh.vertices.col(set.vertices[i]);
    const Eigen::Vector3d expected(1.0 - X[1], X[0] - 1.0, X[2]);  // 90° about z around the elbow (1, 0, 0)
    EXPECT_LT((at.col(static_cast<Eigen::Index>(i)) - expected).norm(), 1e-6);
  }
  std::ostringstream log;
  k["output"]["dir"] = (dir_ / "bone").string();
  EXPECT_TRUE(run_scene(parse_scene(k, dir_ / "s.json"), log).all_converged) << log.str();
  EXPECT_NE(log.str().find("tissue cap: "), std::string::npos);
}

}  // namespace
}  // namespace snh
