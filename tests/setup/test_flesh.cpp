// Skeleton-driven flesh on a procedural limb (a closed cylinder, shoulder → elbow → tip, the elbow bent 90°
// quasi-statically): bound vertices follow their bones exactly, the flesh keeps its volume where linear
// blend skinning loses it, frame 0 is the input surface, lattice and tets agree; and bad flesh scenes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "limb_model.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

class FleshLimb : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("snh-test-flesh-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    test::write_limb_gltf(dir_ / "limb.gltf");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  /// A quasi-static scene of the limb's bend clip.
  static json scene(const std::string& volume, int resolution, const std::string& out) {
    return {{"flesh", {{"model", (dir_ / "limb.gltf").string()}, {"volume", volume}, {"resolution", resolution}}},
            {"frames", 4},
            {"output", {{"dir", (dir_ / out).string()}}}};
  }
  static SceneResult run(const json& j) {
    const Scene s = parse_scene(j, dir_ / "limb.json");
    std::ostringstream log;
    SceneResult r = run_scene(s, log);
    EXPECT_TRUE(r.all_converged) << log.str();
    return r;
  }
  static json stats(const std::string& out) {
    std::ifstream in(dir_ / out / "stats.json");
    return json::parse(in);
  }
  static inline fs::path dir_;
};

TEST_F(FleshLimb, TheEmbeddedSurfaceIsTheInputSurfaceAtRest) {
  for (const char* volume : {"lattice", "tets"}) {
    const BuiltScene built = build_scene(parse_scene(scene(volume, 10, "rest"), dir_ / "limb.json"));
    const Scene& s = built.scene;
    const Flesh& f = *built.body->flesh;
    EXPECT_EQ(f.model.skeleton.size(), 3);
    EXPECT_GT(f.volume.cell_count(), 0);
    EXPECT_EQ(edge_counts(f.model.surface_triangles).open, 0);
    const Eigen::Map<const Eigen::VectorXd> X(f.volume.vertices.data(), f.volume.vertices.size());
    const Eigen::Matrix3Xd at_rest = flesh_surface(f, X);
    EXPECT_LT((at_rest - f.model.vertices).cwiseAbs().maxCoeff(), 1e-12) << volume;
    // The defaults of a flesh scene: quasi-static, the paper's nu = 0.488, the clip's length and 24 fps.
    EXPECT_EQ(s.time.integrator, Integrator::quasi_static);
    EXPECT_NEAR(s.material.params.lambda / (2.0 * (s.material.params.lambda + s.material.params.mu)), 0.488, 1e-12);
    EXPECT_DOUBLE_EQ(built.end_time, 1.0);
    EXPECT_EQ(built.frames, 4);  // given
    // Every segment binds vertices of this volume (the tip, a point on the surface, binds none: warned),
    // and a lattice holds the surface's volume and more.
    for (std::size_t b = 0; b < f.bones.size(); ++b)
      if (f.bones[b].child >= 0) {
        EXPECT_GT(f.bound_per_bone[b], 0) << f.bones[b].name;
      }
    if (std::string(volume) == "lattice") {
      EXPECT_GT(f.volume_of_cells, f.surface_volume);
    }
    else EXPECT_NEAR(f.volume_of_cells, f.surface_volume, 1e-9 * f.surface_volume);
  }
  // Without "frames": the clip's second at 24 frames per second, or at flesh.fps; a material that names an
  // energy alone keeps the flesh's parameters.
  json j = scene("lattice", 6, "rest");
  j.erase("frames");
  j["material"] = {{"name", "neo_hookean"}};
  const BuiltScene at24 = build_scene(parse_scene(j, dir_ / "limb.json"));
  EXPECT_EQ(at24.frames, 24);
  EXPECT_EQ(at24.scene.material.name, "neo_hookean");
  EXPECT_NEAR(youngs_modulus(at24.scene.material.params), 1e5, 1e-6);
  j["flesh"]["fps"] = 30;
  EXPECT_EQ(build_scene(parse_scene(j, dir_ / "limb.json")).frames, 30);
  j["flesh"]["fps"] = 0;
  EXPECT_THROW((void)parse_scene(j, dir_ / "limb.json"), SceneError);
}

TEST_F(FleshLimb, BentElbowKeepsTheFleshVolumeWhereSkinningLosesIt) {
  const SceneResult r = run(scene("lattice", 14, "lattice"));
  ASSERT_EQ(r.frames.size(), 5u);
  const BuiltScene built = build_scene(parse_scene(scene("lattice", 14, "lattice"), dir_ / "limb.json"));
  const Flesh& f = *built.body->flesh;

  // Bound vertices sit exactly where their bones carry them at the last frame (t = 1: the elbow at 90°).
  const std::vector<Eigen::Affine3d> world = joint_world(f, 1.0);
  double worst = 0.0;
  for (std::size_t i = 0; i < f.binding.vertex.size(); ++i) {
    const int v = f.binding.vertex[i], j = f.bones[f.binding.bone[i]].joint;
    const Eigen::Vector3d expected = world[j] * (f.bind_world[j].inverse() * f.volume.vertices.col(v));
    worst = std::max(worst, (r.final_positions.segment<3>(3 * v) - expected).norm());
  }
  EXPECT_LT(worst, 1e-12);
  // The tip bone really turned: the tip joint is at (1, 1, 0).
  EXPECT_LT((world[2].translation() - Eigen::Vector3d(1, 1, 0)).norm(), 1e-6);

  // The render surface's volume: flesh within 2 % at every frame, skinning losing more at the bend.
  const json st = stats("lattice");
  double flesh_loss = 0.0, lbs_loss = 0.0;
  for (const json& fr : st["frames"]) {
    flesh_loss = std::max(flesh_loss, std::abs(fr["surface_volume_ratio"].get<double>() - 1.0));
    lbs_loss = std::max(lbs_loss, std::abs(fr["lbs_volume_ratio"].get<double>() - 1.0));
  }
  EXPECT_LT(flesh_loss, 0.02);
  EXPECT_GT(lbs_loss, 1.5 * flesh_loss) << "flesh " << flesh_loss << ", skinning " << lbs_loss;

  // Frame 0 is the input surface (written to 10 significant digits), in the model's order.
  const SurfaceMesh frame0 = read_surface(dir_ / "lattice" / "surface" / "000.obj");
  EXPECT_LT((frame0.vertices - f.model.vertices).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(frame0.triangles, f.model.triangles);
  EXPECT_TRUE(fs::exists(dir_ / "lattice" / "lbs" / "004.obj"));
  // The USD stage holds both meshes with a point sample per frame.
  std::ifstream usd(dir_ / "lattice" / "flesh.usda");
  std::stringstream text;
  text << usd.rdbuf();
  EXPECT_EQ(text.str().rfind("#usda 1.0", 0), 0u);
  std::size_t samples = 0;
  for (std::size_t at = text.str().find("points.timeSamples"); at != std::string::npos;
       at = text.str().find("points.timeSamples", at + 1))
    ++samples;
  EXPECT_EQ(samples, 2u);
  EXPECT_NE(text.str().find("            4: [("), std::string::npos);
}

TEST_F(FleshLimb, SoftBindingPullsTheShellTowardItsBonesAndStiffensWithItsStiffness) {
  // Shrunken capsules (radius 0.12 of the limb's 0.3) with a shell of 0.2 outside them (the lattice's vertices
  // lie 0.10, 0.23 and 0.31 from the axis): the shell's vertices are pulled toward where their bones carry
  // them, by springs that fade across the shell.
  constexpr double shell = 0.2;
  auto soft_scene = [&](const std::string& out, std::optional<double> stiffness) {
    json j = scene("lattice", 14, out);
    j["flesh"]["bones"] = json::array({{{"joint", "shoulder"}, {"radius", 0.12}}, {{"joint", "elbow"}, {"radius", 0.12}}});
    j["flesh"]["joint_cells"] = "hard";  // the shell alone
    if (stiffness) j["flesh"]["soft_binding"] = {{"shell", shell}, {"stiffness", *stiffness}};
    return j;
  };
  const BuiltScene built = build_scene(parse_scene(soft_scene("soft_rest", 1.0), dir_ / "limb.json"));
  const Flesh& f = *built.body->flesh;
  ASSERT_GT(f.soft.vertex.size(), 0u);
  for (std::size_t i = 0; i < f.soft.vertex.size(); ++i) {  // outside every capsule, within the shell of its own
    const Eigen::Vector3d X = f.volume.vertices.col(f.soft.vertex[i]);
    const Bone& b = f.bones[f.soft.bone[i]];
    const double gap = segment_distance(b.a, b.b, X) - b.radius;
    EXPECT_GT(gap, 0.0);
    EXPECT_LT(gap, shell);
    EXPECT_NEAR(f.soft.weight[i], 1.0 - gap / shell, 1e-12);
    for (const Bone& other : f.bones) EXPECT_GE(segment_distance(other.a, other.b, X) - other.radius, gap - 1e-15);
    EXPECT_EQ(std::find(f.binding.vertex.begin(), f.binding.vertex.end(), f.soft.vertex[i]), f.binding.vertex.end());
  }
  // How far the shell's vertices end from where their bones carry them (weighted), bent to 90°.
  const std::vector<Eigen::Affine3d> world = joint_world(f, 1.0);
  auto shell_miss = [&](const Eigen::VectorXd& x) {
    double sum = 0.0, weights = 0.0;
    for (std::size_t i = 0; i < f.soft.vertex.size(); ++i) {
      const int v = f.soft.vertex[i], j = f.bones[f.soft.bone[i]].joint;
      const Eigen::Vector3d carried = world[j] * (f.bind_world[j].inverse() * f.volume.vertices.col(v));
      sum += f.soft.weight[i] * (x.segment<3>(3 * v) - carried).norm();
      weights += f.soft.weight[i];
    }
    return sum / weights;
  };
  const double none = shell_miss(run(soft_scene("soft_none", std::nullopt)).final_positions);
  double previous = none;
  for (double k : {1.0, 10.0, 100.0}) {
    const double miss = shell_miss(run(soft_scene(fmt::format("soft_{:g}", k), k)).final_positions);
    std::cout << "soft binding " << k << " x E x h: the shell misses its bones by " << miss << " (no soft binding: " << none << ")\n";
    EXPECT_LT(miss, 0.7 * previous) << "stiffness " << k;
    previous = miss;
  }
  const json st = stats("soft_1");
  EXPECT_EQ(st["soft_binding"]["vertices"].get<std::size_t>(), f.soft.vertex.size());
}

TEST_F(FleshLimb, CellsSpanningTheElbowAreHeldByOneJointAtMost) {
  std::map<std::string, std::size_t> released;
  for (const char* mode : {"soft", "free", "hard"}) {
    json j = scene("lattice", 14, std::string("joints_") + mode);
    j["flesh"]["joint_cells"] = mode;
    const BuiltScene built = build_scene(parse_scene(j, dir_ / "limb.json"));
    const Flesh& f = *built.body->flesh;
    released[mode] = f.released.vertex.size();
    std::vector<int> joint(f.volume.vertex_count(), -1);
    for (std::size_t i = 0; i < f.binding.vertex.size(); ++i) joint[f.binding.vertex[i]] = f.bones[f.binding.bone[i]].joint;
    int spanning = 0;  // cells whose hard-bound vertices move with two joints
    for (Eigen::Index c = 0; c < f.volume.cell_count(); ++c) {
      std::set<int> joints;
      for (Eigen::Index k = 0; k < f.volume.cells.rows(); ++k)
        if (joint[f.volume.cells(k, c)] >= 0) joints.insert(joint[f.volume.cells(k, c)]);
      spanning += joints.size() > 1;
    }
    if (std::string(mode) == "hard") {
      EXPECT_GT(spanning, 0) << "the default capsules of the limb meet at the elbow";
      EXPECT_TRUE(f.soft.vertex.empty());
    } else {
      EXPECT_EQ(spanning, 0) << mode;
      EXPECT_GT(f.released.vertex.size(), 0u) << mode;
      EXPECT_EQ(f.soft.vertex, std::string(mode) == "soft" ? f.released.vertex : std::vector<int>{}) << mode;
    }
    // The bend runs in every mode.
    const SceneResult r = run(j);
    EXPECT_EQ(r.frames.size(), 5u) << mode;
  }
  EXPECT_EQ(released["soft"], released["free"]);
  EXPECT_EQ(released["hard"], 0u);
}

// The limb's default capsules (radius about 0.15 on a limb of radius 0.3) both hold the flesh around the
// elbow; bent 90°, the forearm's carries its flesh into the upper arm's. The check names the two bones and the
// frames, its worst pair is the worst of all pairs of bound vertices (found here by brute force), the run warns
// of it and turns flesh inside out there; capsules of 0.4 times the radius leave room, and nothing is pressed.
// Capsules 50 times the radius bind every vertex, so the two bound regions overlap in their interiors.
TEST_F(FleshLimb, CapsulesThatOverlapAsTheElbowBendsAreNamedAndSmallerOnesLeaveRoom) {
  for (const double scale : {1.0, 0.4, 50.0}) {
    json j = scene("lattice", 24, fmt::format("pressed_{}", scale));
    j["flesh"]["radius_scale"] = scale;
    j["frames"] = 16;  // the times checked below
    const BuiltScene built = build_scene(parse_scene(j, dir_ / "limb.json"));
    const std::shared_ptr<const Flesh>& f = built.body->flesh;
    std::vector<double> times;
    for (int k = 1; k <= 16; ++k) times.push_back(k / 16.0);
    const PressedFlesh p = pressed_flesh(f, times);
    // Every pair of bound vertices of the two joints, at every time.
    const double h = f->cell_size;
    double worst = 1.0;
    int worst_frame = -1, frames = 0;
    for (std::size_t k = 0; k < times.size(); ++k) {
      const std::vector<Eigen::Affine3d> world = joint_world(*f, times[k]);
      std::vector<Eigen::Vector3d> at;
      std::vector<int> joint;
      for (std::size_t i = 0; i < f->binding.vertex.size(); ++i) {
        joint.push_back(f->bones[f->binding.bone[i]].joint);
        at.push_back(world[joint.back()] * f->bind_world[joint.back()].inverse() * f->volume.vertices.col(f->binding.vertex[i]));
      }
      double least = 1.0;  // this frame's smallest ratio
      bool pressed = false;
      for (std::size_t a = 0; a < at.size(); ++a)
        for (std::size_t b = a + 1; b < at.size(); ++b) {
          const double d = (at[a] - at[b]).norm();
          const double rest = (f->volume.vertices.col(f->binding.vertex[a]) - f->volume.vertices.col(f->binding.vertex[b])).norm();
          if (joint[a] == joint[b] || d >= 0.5 * h || rest < 2.0 * h * (1.0 - 1e-9)) continue;
          pressed = true;
          least = std::min(least, d / rest);
        }
      frames += pressed;
      if (pressed && least < worst) worst = least, worst_frame = static_cast<int>(k);
      const PressedFlesh one = pressed_flesh(f, {times[k]});  // this frame alone
      EXPECT_EQ(one.frame, pressed ? 0 : -1) << scale << " at t = " << times[k];
      // The check asks only the border vertices of each joint's bound flesh for neighbours: with the limb's
      // capsules the worst pair has one; with everything bound the worst pairs lie deep inside both.
      if (pressed && scale == 1.0) EXPECT_NEAR(one.closest / one.rest, least, 1e-12) << scale << " at t = " << times[k];
      if (pressed) EXPECT_GE(one.closest / one.rest, least - 1e-12) << scale << " at t = " << times[k];
    }
    EXPECT_EQ(p.frames, frames) << scale;
    if (scale != 50.0) EXPECT_EQ(p.frame, worst_frame) << scale;
    const SceneResult r = run(j);
    const json st = stats(fmt::format("pressed_{}", scale));
    int inverted = 0;
    for (const StepRecord& rec : r.frames) inverted += rec.inverted;
    if (scale != 0.4) {
      ASSERT_GE(p.frame, 0) << scale;
      if (scale == 1.0) EXPECT_NEAR(p.closest / p.rest, worst, 1e-12);
      EXPECT_GE(p.rest, 2.0 * h * (1.0 - 1e-9));
      EXPECT_LT(p.closest, 0.5 * h);
      const std::set<std::string> bones = {f->bones[p.bone_a].name, f->bones[p.bone_b].name};
      EXPECT_EQ(bones, (std::set<std::string>{"shoulder>elbow", "elbow>tip"}));
      EXPECT_EQ(st["pressed_flesh"]["frames"], frames);
      EXPECT_EQ(st["pressed_flesh"]["worst_frame"], p.frame + 1);
      EXPECT_GT(inverted, 0) << scale << ": the pressed flesh turns inside out";
    } else {
      EXPECT_EQ(p.frame, -1);
      EXPECT_EQ(frames, 0);
      EXPECT_TRUE(st["pressed_flesh"].is_null());
      EXPECT_EQ(inverted, 0);
      EXPECT_EQ(st["radius_scale"], 0.4);
    }
  }
}

TEST_F(FleshLimb, LatticeAndTetsAgreeInShape) {
  // Two discretizations of the same flesh. The capsules bind the volume vertices that fall inside them, so
  // each volume resolves the bones (and the flesh near them) to its cell size: the bent surfaces differ by
  // up to about one lattice cell (measured gaps 0.13, 0.089, 0.12, 0.068 at resolutions 10, 14, 20, 28,
  // cells 0.20, 0.14, 0.10, 0.072 wide), while the bend moves the tip by 1.4.
  const SceneResult lattice = run(scene("lattice", 14, "shape_lattice"));
  const SceneResult tets = run(scene("tets", 14, "shape_tets"));
  const BuiltScene sl = build_scene(parse_scene(scene("lattice", 14, "shape_lattice"), dir_ / "limb.json"));
  const BuiltScene st = build_scene(parse_scene(scene("tets", 14, "shape_tets"), dir_ / "limb.json"));
  const Eigen::Matrix3Xd a = flesh_surface(*sl.body->flesh, lattice.final_positions);
  const Eigen::Matrix3Xd b = flesh_surface(*st.body->flesh, tets.final_positions);
  const double gap = (a - b).colwise().norm().maxCoeff();
  EXPECT_LT(gap, sl.body->flesh->cell_size);
  const double moved = (a - sl.body->flesh->model.vertices).colwise().norm().maxCoeff();
  EXPECT_GT(moved, 1.0);
}

TEST_F(FleshLimb, TheCommittedLimbIsTheGeneratedOne) {
  // tests/data/flesh/limb.gltf (for the command-line tests) is this generator's output: SNH_RECORD_LIMB=1
  // writes it again.
  const fs::path committed = fs::path(SNH_TEST_DATA) / "flesh" / "limb.gltf";
  if (std::getenv("SNH_RECORD_LIMB")) test::write_limb_gltf(committed);
  std::ifstream a(committed), b(dir_ / "limb.gltf");
  std::stringstream sa, sb;
  sa << a.rdbuf();
  sb << b.rdbuf();
  EXPECT_FALSE(sa.str().empty());
  EXPECT_EQ(sa.str(), sb.str());
}

TEST_F(FleshLimb, BadFleshScenesAreNamed) {
  auto error_of = [&](const json& j) -> std::string {
    try {
      (void)build_scene(parse_scene(j, dir_ / "limb.json"));
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  };
  json j = scene("lattice", 10, "bad");
  auto key = [](double t, double degrees) { return json{{"time", t}, {"axis", {0, 0, 1}}, {"degrees", degrees}}; };
  auto keyframes = [](const std::string& joint, json keys) {
    return json::array({json{{"joints", json::array({joint})}, {"keys", std::move(keys)}}});
  };
  j["flesh"]["keyframes"] = keyframes("knee", json::array({key(0, 0)}));
  EXPECT_NE(error_of(j).find("no joint \"knee\""), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["mesh"] = {{"box", json::object()}};
  EXPECT_NE(error_of(j).find("not both"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["bones"] = json::array({json{{"joint", "tip"}, {"radius", 1e-9}}});
  EXPECT_NE(error_of(j).find("binds no volume vertex"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["animation"] = "wave";
  EXPECT_NE(error_of(j).find("wave"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["model"] = (dir_ / "missing.glb").string();
  EXPECT_NE(error_of(j).find("missing.glb"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["keyframes"] = keyframes("elbow", json::array({key(1, 0), key(1, 5)}));
  EXPECT_NE(error_of(j).find("must increase"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["radius_scale"] = 0;
  EXPECT_NE(error_of(j).find("flesh.radius_scale: must be > 0, got 0"), std::string::npos) << error_of(j);
  j["flesh"]["radius_scale"] = "half";
  EXPECT_NE(error_of(j).find("flesh.radius_scale"), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["joint_cells"] = "loose";
  EXPECT_NE(error_of(j).find("flesh.joint_cells: expected one of soft, free, hard, got \"loose\""), std::string::npos) << error_of(j);
  j = scene("lattice", 10, "bad");
  j["flesh"]["soft_binding"] = {{"shell", 0.0}};
  EXPECT_NE(error_of(j).find("flesh.soft_binding.shell: must be > 0, got 0"), std::string::npos) << error_of(j);
  j["flesh"]["soft_binding"] = {{"shell", 0.1}, {"stiffness", -1}};
  EXPECT_NE(error_of(j).find("flesh.soft_binding.stiffness: must be > 0, got -1"), std::string::npos) << error_of(j);
  j["flesh"]["soft_binding"] = {{"shell", 0.1}, {"stifness", 1}};
  EXPECT_NE(error_of(j).find("flesh.soft_binding.stifness: unknown key"), std::string::npos) << error_of(j);
  // An open surface (the limb without its end caps has two rims of 16 edges) takes a lattice
  // (test_flesh_character), not tets.
  test::LimbOptions open;
  open.caps = false;
  test::write_limb_gltf(dir_ / "open.gltf", open);
  j = scene("tets", 10, "bad");
  j["flesh"]["model"] = (dir_ / "open.gltf").string();
  EXPECT_NE(error_of(j).find("not closed: 32 open and 0 non-manifold edges of"), std::string::npos) << error_of(j);
  EXPECT_NE(error_of(j).find("use the lattice"), std::string::npos) << error_of(j);
  // A resolution and a cell size together.
  j = scene("lattice", 10, "bad");
  j["flesh"]["cell_size"] = 0.1;
  EXPECT_NE(error_of(j).find("give a resolution or a cell_size, not both"), std::string::npos) << error_of(j);
}

}  // namespace
}  // namespace snh
