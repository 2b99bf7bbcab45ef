// Flesh on characters as files deliver them (docs/flesh.md "Your own character"): a skin bound without its
// armature's transform (scale 100, a quarter turn) or in a pose other than the rest pose, honest convergence
// (every converged frame's ‖g‖ within 10 times the tolerance, the step rule derived from it), frames on the
// animation's grid, and the point caches (PC2) that carry the frames back to a DCC.
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
#include "snh/io/pc2.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/rig/bind_pose.hpp"
#include "snh/rig/skinning.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

class Character : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("snh-test-character-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    test::write_limb_gltf(dir_ / "limb.gltf");
    test::write_limb_gltf(dir_ / "placed.gltf", {.armature_scale = 100.0, .armature_degrees = -90.0});
    test::write_limb_gltf(dir_ / "bent_rest.gltf", {.rest_elbow_degrees = 40.0});
    test::write_limb_gltf(dir_ / "long.gltf", {.duration = 1.56});
    test::write_limb_gltf(dir_ / "open.gltf", {.caps = false});
    test::write_limb_gltf(dir_ / "inward.gltf", {.inside_out = true});
    test::write_limb_gltf(dir_ / "parts.gltf", {.two_meshes = true});
    test::write_limb_gltf(dir_ / "still.gltf", {.still_clip_first = true});
    test::write_limb_gltf(dir_ / "beside.gltf", {.beside_gap = 0.04});
    test::write_limb_gltf(dir_ / "cap.gltf", {.rigid_cap = 0.6});
    test::write_limb_gltf(dir_ / "sunk.gltf", {.beside_overlap = 0.2});
    test::write_limb_gltf(dir_ / "seam.gltf", {.degrees = 45.0, .split_at_elbow = true});
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  static json scene(const std::string& model, const std::string& out, int resolution = 10) {
    return {{"flesh", {{"model", (dir_ / model).string()}, {"resolution", resolution}}},
            {"frames", 4},
            {"output", {{"dir", (dir_ / out).string()}}}};
  }
  static SceneResult run(const json& j, std::string* log_out = nullptr) {
    std::ostringstream log;
    SceneResult r = run_scene(parse_scene(j, dir_ / "scene.json"), log);
    EXPECT_TRUE(r.all_converged) << log.str();
    if (log_out) *log_out = log.str();
    return r;
  }
  static json stats(const std::string& out) {
    std::ifstream in(dir_ / out / "stats.json");
    return json::parse(in);
  }
  static inline fs::path dir_;
};

TEST(BindPose, FitSimilarityRecoversAKnownOne) {
  std::srand(7);
  const Eigen::Matrix3Xd p = Eigen::Matrix3Xd::Random(3, 40);
  Similarity truth;
  truth.scale = 37.5;
  truth.rotation = Eigen::AngleAxisd(2.1, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  truth.translation = Eigen::Vector3d(4, -8, 15);
  const Similarity fit = fit_similarity(p, truth.affine() * p);
  EXPECT_NEAR(fit.scale, truth.scale, 1e-10 * truth.scale);
  EXPECT_LT((fit.rotation - truth.rotation).norm(), 1e-12);
  EXPECT_LT((fit.translation - truth.translation).norm(), 1e-10);
  EXPECT_NEAR(fit.angle(), 2.1, 1e-12);
  // A reflection is never fitted: mirrored points get a proper rotation.
  Eigen::Matrix3Xd mirrored = p;
  mirrored.row(0) *= -1.0;
  EXPECT_GT(fit_similarity(p, mirrored).rotation.determinant(), 0.0);
}

// An FBX character converted to glTF: the armature node scales by 100 and turns a quarter about x, and the
// inverse bind matrices leave that out. Before, every bone stood 100 times too far from the flesh and the
// build said "no volume vertex lies inside a bone's capsule". The flesh is built where the rest pose puts
// the skin; quasi-statically the physics does not see a similarity, so every frame is the plain limb's,
// placed.
TEST_F(Character, AnArmatureLeftOutOfTheSkinPlacesTheFleshWhereTheRestPoseDoes) {
  RiggedModel model = read_model(dir_ / "placed.gltf");
  const RiggedModel stored = model;
  const std::vector<Eigen::Affine3d> rest = model.skeleton.world(model.skeleton.rest_pose());
  const BindPose bind = place_at_bind_pose(model);
  EXPECT_TRUE(bind.placed);
  EXPECT_TRUE(bind.rest_is_bind);
  EXPECT_NEAR(bind.placement.scale, 100.0, 1e-4);
  EXPECT_NEAR(bind.placement.angle() * 180.0 / std::numbers::pi, 90.0, 1e-4);
  // The placed skin is the skin posed at rest, and skinning any pose gives what it gave before.
  EXPECT_LT((model.vertices - skin_vertices(stored, rest)).cwiseAbs().maxCoeff(), 1e-4);
  for (double t : {0.0, 0.4, 1.0}) {
    const auto world = model.skeleton.world(sample(model.clips.front(), model.skeleton, t));
    EXPECT_LT((skin_vertices(model, world) - skin_vertices(stored, world)).cwiseAbs().maxCoeff(), 1e-9 * 300.0) << t;
  }
  EXPECT_NE(describe(bind).find("scaled 100x"), std::string::npos) << describe(bind);

  std::string log;
  const SceneResult placed = run(scene("placed.gltf", "placed"), &log);
  EXPECT_NE(log.find("placement: the rest pose puts the skin scaled 100x, turned 90.0 degrees"), std::string::npos) << log;
  const SceneResult plain = run(scene("limb.gltf", "plain"));
  ASSERT_EQ(placed.frames.size(), plain.frames.size());
  const Eigen::Affine3d a = bind.placement.affine();
  for (const char* frame : {"000.obj", "002.obj", "004.obj"}) {
    const Eigen::Matrix3Xd p = read_surface(dir_ / "placed" / "surface" / frame).vertices;
    const Eigen::Matrix3Xd q = a * read_surface(dir_ / "plain" / "surface" / frame).vertices;
    // 100 model units across; the OBJ frames hold 10 significant digits; each run's Newton tolerance.
    EXPECT_LT((p - q).cwiseAbs().maxCoeff(), 1e-5 * 100.0) << frame;
  }
  EXPECT_TRUE(stats("placed")["bind_pose"]["placed"].get<bool>());
  EXPECT_FALSE(stats("plain")["bind_pose"]["placed"].get<bool>());
}

// A character bound straight but resting with its elbow bent: bones are placed in the bind pose (the rest
// pose's forearm bone would run out of the straight flesh), the header says so, and the clip, which starts
// straight, leaves frame 0 at the stored skin.
TEST_F(Character, ARestPoseThatIsNotTheBindPoseBindsTheFleshInTheBindPose) {
  std::string log;
  const SceneResult r = run(scene("bent_rest.gltf", "bent_rest"), &log);
  EXPECT_NE(log.find("bind pose: the rest pose differs from the pose the skin was bound in (joint tip"), std::string::npos) << log;
  const BuiltScene built = build_scene(parse_scene(scene("bent_rest.gltf", "bent_rest"), dir_ / "scene.json"));
  const Flesh& f = *built.body->flesh;
  EXPECT_FALSE(f.bind.rest_is_bind);
  for (const Bone& b : f.bones) {  // every bone on the straight limb's axis
    EXPECT_LT(std::hypot(b.a.y(), b.a.z()), 1e-6) << b.name;
    EXPECT_LT(std::hypot(b.b.y(), b.b.z()), 1e-6) << b.name;
  }
  const Eigen::Matrix3Xd frame0 = read_surface(dir_ / "bent_rest" / "surface" / "000.obj").vertices;
  EXPECT_LT((frame0 - f.model.vertices).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(r.frames.size(), 5u);
}

// Honest convergence: every frame that says converged has ‖g‖ within 10 times the tolerance stats.json
// reports, and the flesh's step rule is the tolerance's displacement through (λ + 2μ) h. Before, at ν =
// 0.488 the step rule (1e-4 h) ended frames with ‖g‖ up to 800 times the tolerance.
TEST_F(Character, AConvergedFrameHasItsForceResidualWithinTenTimesTheTolerance) {
  (void)run(scene("limb.gltf", "honest", 12));
  const json st = stats("honest");
  const double tol = st["tolerance"].get<double>(), lambda = st["lambda"].get<double>(), mu = st["mu"].get<double>();
  const BuiltScene built = build_scene(parse_scene(scene("limb.gltf", "honest", 12), dir_ / "scene.json"));
  EXPECT_NEAR(st["step_tolerance"].get<double>(), tol / ((lambda + 2.0 * mu) * built.body->flesh->cell_size), 1e-12 * tol);
  int frames = 0;
  for (const json& fr : st["frames"]) {
    if (fr["frame"].get<int>() == 0) continue;
    ++frames;
    EXPECT_TRUE(fr["converged"].get<bool>());
    EXPECT_LE(fr["residual"].get<double>(), 10.0 * tol) << "frame " << fr["frame"];
    EXPECT_TRUE(fr.contains("newton_step"));
    EXPECT_EQ(fr["inverted"].get<int>(), 0);
  }
  EXPECT_EQ(frames, 4);
}

// Frames on the animation's grid: a 1.56 s clip at 24 fps runs 38 frames to 38/24 s (not 37 frames 1.56/37
// apart), and the USD stage plays at 24 time codes a second.
TEST_F(Character, FramesLieOnTheClipsGridAtItsFramesPerSecond) {
  json j = scene("long.gltf", "grid", 6);
  j.erase("frames");
  const BuiltScene built = build_scene(parse_scene(j, dir_ / "scene.json"));
  EXPECT_EQ(built.frames, 38);
  EXPECT_DOUBLE_EQ(built.end_time, 38.0 / 24.0);
  EXPECT_DOUBLE_EQ(built.end_time / built.frames, 1.0 / 24.0);
  j["flesh"]["fps"] = 30;
  EXPECT_EQ(build_scene(parse_scene(j, dir_ / "scene.json")).frames, 47);  // 1.56 × 30 = 46.8, rounded up
  j["flesh"]["fps"] = 25;
  EXPECT_EQ(build_scene(parse_scene(j, dir_ / "scene.json")).frames, 39);  // 39 exactly
}

// The point caches hold the OBJ frames, sample k at frame k, in the model's vertex order.
TEST_F(Character, PointCachesHoldTheFramesInTheModelsOrder) {
  (void)run(scene("limb.gltf", "cache"));
  const json st = stats("cache");
  EXPECT_EQ(st["pc2"]["flesh"], "flesh.pc2");
  std::ifstream usd(dir_ / "cache" / "flesh.usda");
  std::stringstream text;
  text << usd.rdbuf();
  EXPECT_NE(text.str().find("timeCodesPerSecond = 4"), std::string::npos);  // 4 frames over the 1 s clip
  for (const auto& [file, dir] : {std::pair{"flesh.pc2", "surface"}, std::pair{"lbs.pc2", "lbs"}}) {
    const std::vector<Eigen::Matrix3Xd> samples = read_pc2(dir_ / "cache" / file);
    ASSERT_EQ(samples.size(), 5u) << file;
    for (int k = 0; k < 5; ++k) {
      const Eigen::Matrix3Xd obj = read_surface(dir_ / "cache" / dir / fmt::format("{:03d}.obj", k)).vertices;
      ASSERT_EQ(samples[k].cols(), obj.cols());
      EXPECT_LT((samples[k] - obj).cwiseAbs().maxCoeff(), 1e-6 * 3.0) << file << " " << k;  // single precision
    }
  }
}

// Skins as characters have them: holes (the limb without its end caps: 32 open edges), triangles turned
// inside out, and a character in two meshes (each node half of the triangles). Before, each was refused
// (or the second mesh dropped without a word); now each runs, and the inside-out and two-part limbs give the
// plain limb's frames exactly (the same welded surface, the same lattice).
TEST_F(Character, OpenInsideOutAndManyPartSkinsRun) {
  std::string log;
  (void)run(scene("limb.gltf", "whole"));
  (void)run(scene("open.gltf", "open"), &log);
  EXPECT_NE(log.find("skin: 32 open and 0 non-manifold edges"), std::string::npos) << log;
  EXPECT_EQ(stats("open")["open_edges"].get<int>(), 32);
  (void)run(scene("inward.gltf", "inward"), &log);
  EXPECT_NE(log.find("its triangles face inwards"), std::string::npos) << log;
  EXPECT_TRUE(stats("inward")["inside_out"].get<bool>());
  (void)run(scene("parts.gltf", "parts"), &log);
  EXPECT_NE(log.find("skin: 2 skinned meshes, limb (386), limb_far (386)"), std::string::npos) << log;
  EXPECT_EQ(stats("parts")["parts"].size(), 2u);
  // A cache per mesh: each holds its own vertices of the whole cache.
  const std::vector<Eigen::Matrix3Xd> whole_cache = read_pc2(dir_ / "parts" / "flesh.pc2");
  ASSERT_EQ(stats("parts")["pc2"]["meshes"].size(), 2u);
  for (const json& m : stats("parts")["pc2"]["meshes"]) {
    const std::vector<Eigen::Matrix3Xd> part = read_pc2(dir_ / "parts" / m["file"].get<std::string>());
    ASSERT_EQ(part.size(), whole_cache.size());
    EXPECT_EQ(part.back(), whole_cache.back().middleCols(m["first_vertex"].get<Eigen::Index>(), m["vertices"].get<Eigen::Index>()));
  }
  EXPECT_TRUE(fs::exists(dir_ / "parts" / "flesh_limb.pc2") && fs::exists(dir_ / "parts" / "flesh_limb_far.pc2"));
  EXPECT_EQ(stats("whole")["cells"], stats("inward")["cells"]);
  EXPECT_EQ(stats("whole")["cells"], stats("parts")["cells"]);
  for (const char* frame : {"000.obj", "004.obj"}) {
    const Eigen::Matrix3Xd whole = read_surface(dir_ / "whole" / "surface" / frame).vertices;
    EXPECT_LT((read_surface(dir_ / "inward" / "surface" / frame).vertices - whole).cwiseAbs().maxCoeff(), 1e-9) << frame;
    const Eigen::Matrix3Xd parts = read_surface(dir_ / "parts" / "surface" / frame).vertices;
    ASSERT_EQ(parts.cols(), 2 * whole.cols());
    EXPECT_LT((parts.leftCols(whole.cols()) - whole).cwiseAbs().maxCoeff(), 1e-9) << frame;
    EXPECT_LT((parts.rightCols(whole.cols()) - whole).cwiseAbs().maxCoeff(), 1e-9) << frame;
  }
  // The open limb's lattice holds its inside (the winding number at every cube) and no more than the closed one's.
  const int open_cells = stats("open")["cells"].get<int>(), whole_cells = stats("whole")["cells"].get<int>();
  EXPECT_GE(open_cells, whole_cells * 9 / 10);
  EXPECT_LE(open_cells, whole_cells);
}

// Parts closer than a cell are not glued together (the virtual node algorithm): a limb bends beside a still
// one 0.04 away, a third of a cell. With one cell per cube the cells over the gap drag the still limb along;
// with a cell per piece it stays where it is, and the header and stats.json say how many cubes were split.
TEST_F(Character, PartsCloserThanACellAreNotGluedTogether) {
  std::string log;
  json j = scene("beside.gltf", "beside", 16);
  (void)run(j, &log);
  EXPECT_NE(log.find("the skin separates material closer than a cube"), std::string::npos) << log;
  EXPECT_GT(stats("beside")["copied_vertices"].get<int>(), 0);
  j["flesh"]["split_cells"] = false;
  j["output"]["dir"] = (dir_ / "glued").string();
  (void)run(j);
  EXPECT_EQ(stats("glued")["copied_vertices"].get<int>(), 0);
  EXPECT_LT(stats("beside")["cell_size"].get<double>(), 0.14);  // the gap is under a third of a cell
  // The still limb: the second half of the model's vertices. How far its skin moved by the last frame.
  const auto moved = [&](const std::string& out) {
    const Eigen::Matrix3Xd rest = read_surface(dir_ / out / "surface" / "000.obj").vertices;
    const Eigen::Matrix3Xd last = read_surface(dir_ / out / "surface" / "004.obj").vertices;
    const Eigen::Index half = rest.cols() / 2;
    return (last.rightCols(half) - rest.rightCols(half)).colwise().norm().maxCoeff();
  };
  const double apart = moved("beside"), glued = moved("glued");
  EXPECT_GT(glued, 0.05) << "glued, the still limb follows the bending one";
  EXPECT_LT(apart, 1e-3) << "apart, it stays (glued: " << glued << ")";
}

// Meshes whose skins share no joint are separate solids: a still limb sunk 0.2 into a bending one (a hand
// resting in a thigh) is not dragged along, each held only by its own joints' bones. --join-meshes (the scene's
// "join_meshes") makes one solid of them, and the bending limb then drags the still one.
TEST_F(Character, MeshesWhoseSkinsShareNoJointOverlapWithoutFusing) {
  std::string log;
  json j = scene("sunk.gltf", "sunk", 16);
  (void)run(j, &log);
  EXPECT_NE(log.find("volume: 2 solids, kept apart where they overlap"), std::string::npos) << log;
  EXPECT_EQ(stats("sunk")["solids"].size(), 2u);
  j["flesh"]["join_meshes"] = true;
  j["output"]["dir"] = (dir_ / "fused").string();
  std::string fused_log;
  (void)run(j, &fused_log);
  EXPECT_EQ(fused_log.find("solids"), std::string::npos) << fused_log;
  EXPECT_EQ(stats("fused")["solids"].size(), 1u);
  // The still limb: the vertices skinned to its joint ("still", joint 3).
  const RiggedModel m = read_model(dir_ / "sunk.gltf");
  const auto moved = [&](const std::string& out) {
    const Eigen::Matrix3Xd rest = read_surface(dir_ / out / "surface" / "000.obj").vertices;
    const Eigen::Matrix3Xd last = read_surface(dir_ / out / "surface" / "004.obj").vertices;
    double most = 0.0;
    int still = 0;
    for (Eigen::Index v = 0; v < rest.cols(); ++v)
      if (m.joint_index(0, v) == 3 && m.joint_weight(0, v) == 1.0) most = std::max(most, (last.col(v) - rest.col(v)).norm()), ++still;
    EXPECT_GT(still, 300);
    return most;
  };
  const double apart = moved("sunk"), fused = moved("fused");
  EXPECT_GT(fused, 0.05) << "one solid: the still limb follows the bending one";
  EXPECT_LT(apart, 1e-3) << "two solids: it stays (fused: " << fused << ")";
}

// Two meshes that share no joint but meet along a seam (the limb cut at the elbow, the upper half skinned to the
// shoulder, the lower to the elbow, each with its own copy of the seam's ring) are glued at the seam: the skin
// does not open there as the elbow bends, though skinning alone would tear it.
TEST_F(Character, SolidsMeetingAtASeamAreGluedThere) {
  std::string log;
  (void)run(scene("seam.gltf", "seam", 16), &log);
  const json st = stats("seam");
  EXPECT_EQ(st["solids"].size(), 2u);
  EXPECT_EQ(st["seam_vertices"].get<int>(), 16) << log;  // one ring of 16
  const RiggedModel m = read_model(dir_ / "seam.gltf");
  ASSERT_EQ(m.parts.size(), 2u);
  const Eigen::Matrix3Xd last = read_surface(dir_ / "seam" / "surface" / "004.obj").vertices;
  const Eigen::Matrix3Xd lbs = skin_vertices(m, m.skeleton.world(sample(m.clips[0], m.skeleton, 1.0)));
  // The meshes share one vertex buffer: each lists all vertices; a seam vertex is one the first mesh's
  // triangles use at the place of one the second mesh's triangles use.
  std::vector<int> used_by(static_cast<std::size_t>(m.vertices.cols()), 0);
  for (Eigen::Index t = 0; t < m.triangles.cols(); ++t)
    for (int c = 0; c < 3; ++c)
      used_by[static_cast<std::size_t>(m.triangles(c, t))] |= m.triangles(c, t) < m.parts[1].first_vertex ? 1 : 2;
  double gap = 0.0, lbs_gap = 0.0;  // between the two copies of each seam vertex
  int pairs = 0;
  for (Eigen::Index a = 0; a < m.parts[1].first_vertex; ++a)
    for (Eigen::Index b = m.parts[1].first_vertex; b < m.vertices.cols(); ++b)
      if (used_by[static_cast<std::size_t>(a)] && used_by[static_cast<std::size_t>(b)] && m.joint_weight(0, a) != m.joint_weight(0, b) &&
          (m.vertices.col(a) - m.vertices.col(b)).norm() < 1e-9) {
        ++pairs;
        gap = std::max(gap, (last.col(a) - last.col(b)).norm());
        lbs_gap = std::max(lbs_gap, (lbs.col(a) - lbs.col(b)).norm());
      }
  EXPECT_EQ(pairs, 16);
  EXPECT_GT(lbs_gap, 0.05) << "skinning tears the seam open";
  EXPECT_LT(gap, 1e-9) << "the flesh keeps it closed";
}

// A mesh without a skin under a joint (a prop held 0.5 beyond the tip) is read as part of the character, bound
// wholly to that joint: at the end of the clip it has turned with the forearm, a quarter turn about the elbow.
// In a flesh run it is a part of the volume of its own that no bone's capsule reaches: it follows its joint whole.
TEST_F(Character, AMeshWithoutASkinUnderAJointFollowsIt) {
  const RiggedModel m = read_model(dir_ / "cap.gltf");
  ASSERT_EQ(m.parts.size(), 2u);
  EXPECT_EQ(m.parts[1].name, "cap");
  EXPECT_EQ(m.parts[1].vertices, 8);
  ASSERT_EQ(m.notes.size(), 1u);
  EXPECT_EQ(m.notes[0], "mesh \"cap\" has no skin: it follows joint \"tip\" rigidly");
  const Eigen::Index first = m.parts[1].first_vertex;
  const Eigen::Matrix3Xd rest = m.vertices.middleCols(first, 8);
  EXPECT_NEAR(rest.row(0).mean(), 2.6, 1e-6);  // 0.6 beyond the tip at x = 2
  EXPECT_LT(rest.bottomRows(2).cwiseAbs().maxCoeff(), 0.1 + 1e-6);
  const Eigen::Matrix3Xd end = skin_vertices(m, m.skeleton.world(sample(m.clips[0], m.skeleton, 1.0)));
  const Eigen::Matrix3d quarter = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d elbow(1.0, 0.0, 0.0);
  for (Eigen::Index v = 0; v < 8; ++v)
    EXPECT_LT((end.col(first + v) - (quarter * (rest.col(v) - elbow) + elbow)).norm(), 1e-6) << "cap vertex " << v;
  // A flesh run carries it: the prop is its own solid, moved whole by its joint.
  std::string log;
  (void)run(scene("cap.gltf", "cap", 16), &log);
  EXPECT_NE(log.find("model: mesh \"cap\" has no skin"), std::string::npos) << log;
  EXPECT_NE(log.find("bones: 1 parts of the volume hold no bone's capsule and follow the joint their skin is weighted to, whole"),
            std::string::npos) << log;
  EXPECT_NE(log.find(" vertices to tip)"), std::string::npos) << log;
  EXPECT_EQ(stats("cap")["free_parts"].size(), 1u);
  const Eigen::Matrix3Xd last = read_surface(dir_ / "cap" / "surface" / "004.obj").vertices;
  EXPECT_LT((last.middleCols(first, 8) - end.middleCols(first, 8)).cwiseAbs().maxCoeff(), 1e-3);
}

// A flesh frame may take 200 Newton iterations (a joint bent far needs over 100), the paper programs' scenes 50;
// the scene's solver.max_iterations (snh flesh --newton-iterations) sets it, and the header and stats.json say it.
TEST_F(Character, AFleshFrameMayTakeTwoHundredNewtonIterations) {
  std::string log;
  json j = scene("limb.gltf", "newton_default");
  (void)run(j, &log);
  EXPECT_EQ(stats("newton_default")["max_newton_iterations"].get<int>(), 200);
  EXPECT_NE(log.find("or fails after 200 iterations"), std::string::npos) << log;
  j["solver"] = {{"max_iterations", 1}};
  j["output"]["dir"] = (dir_ / "newton_one").string();
  std::ostringstream one;
  const SceneResult r = run_scene(parse_scene(j, dir_ / "scene.json"), one);
  EXPECT_EQ(stats("newton_one")["max_newton_iterations"].get<int>(), 1);
  EXPECT_FALSE(r.all_converged) << one.str();
  EXPECT_NE(one.str().find("no convergence in 1 Newton iterations"), std::string::npos) << one.str();
}

// The clip played by default is the first that lasts and moves: a one-key "bind" clip, as FBX conversions
// write, is skipped.
TEST_F(Character, AStillClipIsNotPlayedByDefault) {
  const RiggedModel m = read_model(dir_ / "still.gltf");
  ASSERT_EQ(m.clips.size(), 2u);
  EXPECT_FALSE(m.clips[0].moves());
  EXPECT_TRUE(m.clips[1].moves());
  EXPECT_EQ(default_clip(m), 1);
  json j = scene("still.gltf", "still");
  const BuiltScene built = build_scene(parse_scene(j, dir_ / "scene.json"));
  EXPECT_EQ(built.body->flesh->clip.name, "bend");
  j["flesh"]["animation"] = "bind";  // asked for by name, it is played
  EXPECT_EQ(build_scene(parse_scene(j, dir_ / "scene.json")).body->flesh->clip.name, "bind");
}

// The lattice's resolution: given, from a cell size in model units, or chosen from the bones so that every
// capsule holds a lattice node (at least 16).
TEST_F(Character, TheResolutionComesFromACellSizeOrTheBones) {
  json j = scene("limb.gltf", "res");
  j["flesh"].erase("resolution");
  j["flesh"]["cell_size"] = 0.1;  // the limb is 2.0 long
  const BuiltScene sized = build_scene(parse_scene(j, dir_ / "scene.json"));
  EXPECT_EQ(sized.body->flesh->resolution, 20);
  EXPECT_NEAR(sized.body->flesh->cell_size, 0.1, 0.01);
  j["flesh"].erase("cell_size");
  const BuiltScene chosen = build_scene(parse_scene(j, dir_ / "scene.json"));
  const Flesh& f = *chosen.body->flesh;
  EXPECT_GE(f.resolution, 16);
  EXPECT_NE(f.resolution_reason.find(f.resolution == 16 ? "the default 16" : "thinnest capsule"), std::string::npos);
  for (std::size_t b = 0; b < f.bones.size(); ++b)
    if (f.bones[b].child >= 0) {
      EXPECT_GT(f.bound_per_bone[b], 0) << f.bones[b].name;
    }
  // A thin limb (radius 0.03 over a length of 2): resolution 16 would leave its bones' capsules empty.
  test::write_limb_gltf(dir_ / "thin.gltf", {.radius = 0.03});
  j["flesh"]["model"] = (dir_ / "thin.gltf").string();
  const BuiltScene thin = build_scene(parse_scene(j, dir_ / "scene.json"));
  const Flesh& t = *thin.body->flesh;
  EXPECT_GT(t.resolution, 16);
  EXPECT_NE(t.resolution_reason.find("thinnest capsule"), std::string::npos) << t.resolution_reason;
  for (std::size_t b = 0; b < t.bones.size(); ++b)
    if (t.bones[b].child >= 0) {
      EXPECT_GT(t.bound_per_bone[b], 0) << t.bones[b].name;
    }
  j["flesh"]["resolution"] = 16;
  EXPECT_THROW((void)build_scene(parse_scene(j, dir_ / "scene.json")), std::invalid_argument);
}

TEST(Pc2, WritesWhatItReadsAndRefusesWhatItCannotHold) {
  const fs::path path = fs::temp_directory_path() / ("snh-test-pc2-" + std::to_string(::getpid()) + ".pc2");
  std::vector<Eigen::Matrix3Xd> samples{Eigen::Matrix3Xd::Random(3, 7), Eigen::Matrix3Xd::Random(3, 7)};
  write_pc2(path, samples, 1.0, 0.5);
  EXPECT_EQ(fs::file_size(path), 32u + 2u * 7u * 12u);
  const std::vector<Eigen::Matrix3Xd> back = read_pc2(path);
  ASSERT_EQ(back.size(), 2u);
  for (int k = 0; k < 2; ++k) EXPECT_LT((back[k] - samples[k]).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_THROW(write_pc2(path, {}), std::invalid_argument);
  EXPECT_THROW(write_pc2(path, {Eigen::Matrix3Xd::Zero(3, 2), Eigen::Matrix3Xd::Zero(3, 3)}), std::invalid_argument);
  Eigen::Matrix3Xd bad = Eigen::Matrix3Xd::Zero(3, 2);
  bad(1, 1) = 1e300;  // beyond single precision
  EXPECT_THROW(write_pc2(path, {bad}), std::invalid_argument);
  bad(1, 1) = std::nan("");
  EXPECT_THROW(write_pc2(path, {bad}), std::invalid_argument);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "POINTCACHE2";  // truncated
  EXPECT_THROW((void)read_pc2(path), std::runtime_error);
  fs::remove(path);
}

}  // namespace
}  // namespace snh
