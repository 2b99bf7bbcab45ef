// Rigged characters in the formats DCCs export (docs/flesh.md "Formats"), read by read_model: glTF by our own
// reader, FBX and COLLADA through assimp.
//   * A character made in Blender (tests/apps/blender_character.py, run here in Debian's Blender in background
//     mode) and exported by Blender's own glTF, FBX and COLLADA exporters: each file's linear blend skinning
//     over the clip matches Blender's own skinning of the character, up to the one similarity that each
//     exporter's axes and units make (fitted on the bones' heads at the first frame, never on the skin).
//   * Debian's assimp-testmodels: the five rigged, animated characters read directly, with the joints, clips
//     and meshes their files hold; and the errors read_assimp gives for files it cannot use.
// Tests that need Blender or assimp-testmodels are skipped where they are not installed (CI installs both).
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "rig_error.hpp"
#include "snh/rig/assimp.hpp"
#include "snh/rig/bind_pose.hpp"
#include "snh/rig/model.hpp"
#include "snh/rig/normals.hpp"
#include "snh/rig/skinning.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kAssimpModels = "/usr/share/assimp/models";

/// The first key time of a clip over all channels (exporters start a clip at their first frame's time).
double first_key(const Clip& clip) {
  double t = 1e300;
  for (const Channel& c : clip.channels)
    if (!c.times.empty()) t = std::min(t, c.times.front());
  return t;
}

/// The largest distance from a point of `a` to the nearest point of `b`, and back (Hausdorff over vertices).
double hausdorff(const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b) {
  const auto one_way = [](const Eigen::Matrix3Xd& p, const Eigen::Matrix3Xd& q) {
    double worst = 0.0;
    for (Eigen::Index i = 0; i < p.cols(); ++i) worst = std::max(worst, std::sqrt((q.colwise() - p.col(i)).colwise().squaredNorm().minCoeff()));
    return worst;
  };
  return std::max(one_way(a, b), one_way(b, a));
}

class BlenderCharacter : public ::testing::Test {
 protected:
  // Each test runs in a process of its own (gtest_discover_tests): Blender makes the character once per
  // build and script, into a directory of the build tree named after the script's contents, moved into place
  // whole (tests running side by side keep whichever comes first).
  static void SetUpTestSuite() {
    if (std::system("command -v blender > /dev/null 2>&1") != 0) return;
    const fs::path script = fs::path(SNH_TESTS_DIR) / "apps" / "blender_character.py";
    std::ifstream source(script);
    const std::string text(std::istreambuf_iterator<char>(source), {});
    dir_ = fs::path(SNH_TESTS_BINARY_DIR) / fmt::format("blender_character-{:016x}", std::hash<std::string>{}(text));
    made_ = fs::exists(dir_ / "truth.json");
    if (!made_) {
      const fs::path work = dir_.string() + ".tmp." + std::to_string(::getpid());
      const std::string cmd = fmt::format("blender -b --factory-startup --python-exit-code 1 -P '{}' -- '{}' > '{}.log' 2>&1",
                                          script.string(), work.string(), work.string());
      made_ = std::system(cmd.c_str()) == 0;
      std::ifstream log(work.string() + ".log");
      log_ = std::string(std::istreambuf_iterator<char>(log), {});
      std::error_code ec;
      if (made_) fs::rename(work, dir_, ec);  // fails where another test's copy is there first: that one is used
      fs::remove_all(work, ec);
      fs::remove(work.string() + ".log", ec);
      made_ = made_ && fs::exists(dir_ / "truth.json");
      if (!made_) return;
    }
    std::ifstream in(dir_ / "truth.json");
    truth_ = json::parse(in);
  }
  void SetUp() override {
    if (dir_.empty()) GTEST_SKIP() << "blender is not installed (scripts/install-deps installs it)";
    ASSERT_TRUE(made_) << "Blender failed to make the character:\n" << log_;
  }

  /// The similarity that maps the file's joint heads at the clip's first key onto Blender's bone heads (and
  /// that first key's time).
  static Similarity to_blender(const RiggedModel& m, const std::string& file, const std::string& prefix, double& t0) {
    const Clip& clip = m.clips[0];
    t0 = first_key(clip);
    const std::vector<Eigen::Affine3d> first = m.skeleton.world(sample(clip, m.skeleton, t0));
    Eigen::Matrix3Xd ours(3, 3), theirs(3, 3);
    int k = 0;
    for (const char* name : {"upper", "lower", "hand"}) {
      const int j = m.skeleton.find(prefix + name);
      EXPECT_GE(j, 0) << file << ": no joint " << prefix + name;
      if (j < 0) return {};
      ours.col(k) = first[static_cast<std::size_t>(j)].translation();
      const auto h = truth_["heads"][name];
      theirs.col(k++) = Eigen::Vector3d(h[0].get<double>(), h[1].get<double>(), h[2].get<double>());
    }
    const Similarity s = fit_similarity(ours, theirs);
    EXPECT_LT((s.affine() * ours - theirs).cwiseAbs().maxCoeff(), 1e-5) << file << ": the joints do not fit Blender's by a similarity";
    return s;
  }

  /// Points per Blender frame ("1", "12", "24") from a truth file's "frames".
  static Eigen::Matrix3Xd blender_points(const json& points) {
    Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(points.size()));
    for (std::size_t i = 0; i < points.size(); ++i)
      for (int c = 0; c < 3; ++c) out(c, static_cast<Eigen::Index>(i)) = points[i][static_cast<std::size_t>(c)].get<double>();
    return out;
  }

  /// The file's skin at Blender's frames 1, 12 and 24, taken to Blender's world by the similarity that maps
  /// the file's joint heads at the first frame onto Blender's bone heads; compared with Blender's own skin.
  static void expect_blender_skinning(const std::string& file, const std::string& prefix) {
    RiggedModel m = read_model(dir_ / file);
    const BindPose bind = place_at_bind_pose(m);
    EXPECT_TRUE(bind.rest_is_bind) << file << ": " << bind.worst_joint << " by " << bind.worst_offset;
    ASSERT_EQ(m.clips.size(), 1u);
    const Clip& clip = m.clips[0];
    double t0 = 0.0;
    const Similarity s = to_blender(m, file, prefix, t0);
    const double fps = truth_["fps"].get<double>();
    // Blender works in metres, Z up: the unit and up axis the model says are the similarity's scale and the
    // axis its rotation takes to +Z.
    EXPECT_NEAR(s.scale, m.meters_per_unit, 1e-6 * m.meters_per_unit) << file;
    const Eigen::Vector3d up = m.up_sign * Eigen::Vector3d::Unit(m.up_axis);
    EXPECT_GT((s.rotation * up).z(), 1.0 - 1e-6) << file << ": its up axis " << up.transpose();
    for (const auto& [frame, points] : truth_["frames"].items()) {
      const int f = std::stoi(frame);
      const double t = t0 + (f - truth_["first_frame"].get<int>()) / fps;
      const Eigen::Matrix3Xd skin = s.affine() * skin_vertices(m, m.skeleton.world(sample(clip, m.skeleton, t)));
      // The arm is 1.2 long; files store single precision.
      EXPECT_LT(hausdorff(skin, blender_points(points)), 1e-4) << file << " at Blender's frame " << f << " (t = " << t << ")";
    }
  }

  /// A flesh run of one of the files (resolution 10) into `out`; whether every frame converged, and its log.
  static bool run_flesh(const std::string& file, int frames, const fs::path& out, std::string& log) {
    const json scene = {{"flesh", {{"model", (dir_ / file).string()}, {"resolution", 10}}},
                        {"frames", frames},
                        {"output", {{"dir", out.string()}}}};
    std::ostringstream text;
    const SceneResult r = run_scene(parse_scene(scene, dir_ / "scene.json"), text);
    log = text.str();
    return r.all_converged;
  }

  /// What check_usda.py says of the run's flesh.usda (two meshes, `samples` time samples each), and its exit code.
  static std::string check_stage(const fs::path& out, int samples, int& code) {
    const std::string check = fmt::format("python3 '{}/apps/check_usda.py' '{}' 2 {} > '{}' 2>&1", SNH_TESTS_DIR,
                                          (out / "flesh.usda").string(), samples, (out / "usda.log").string());
    code = std::system(check.c_str());
    std::ifstream usda_log(out / "usda.log");
    return std::string(std::istreambuf_iterator<char>(usda_log), {});
  }

  static inline fs::path dir_;
  static inline bool made_ = false;
  static inline std::string log_;
  static inline json truth_;
};

TEST_F(BlenderCharacter, GltfExportSkinsAsBlenderDoes) { expect_blender_skinning("character.glb", ""); }

// Blender's FBX exporter writes centimetres (UnitScaleFactor 1, the armature scaled by 100) and, by
// default, Y up; asked to keep Blender's axes, Z up. Both skin as Blender does, and say so.
TEST_F(BlenderCharacter, FbxExportReadThroughAssimpSkinsAsBlenderDoes) {
  const RiggedModel m = read_model(dir_ / "character.fbx");
  EXPECT_NE(m.format.find("FBX"), std::string::npos) << m.format;
  EXPECT_EQ(m.meters_per_unit, 0.01);
  EXPECT_EQ(m.up_axis, 1);
  expect_blender_skinning("character.fbx", "");
  const RiggedModel z = read_model(dir_ / "character_zup.fbx");
  EXPECT_EQ(z.up_axis, 2);
  EXPECT_EQ(z.up_sign, 1);
  EXPECT_NE(std::find_if(z.notes.begin(), z.notes.end(), [](const std::string& n) { return n.find("up axis: the file says +Z") == 0; }),
            z.notes.end());
  expect_blender_skinning("character_zup.fbx", "");
}

TEST_F(BlenderCharacter, ColladaExportReadThroughAssimpSkinsAsBlenderDoes) { expect_blender_skinning("character.dae", "rig_"); }

// A prop parented to the hand bone, without a skin: read from glTF and FBX as a part of the character bound
// wholly to the hand, it moves as Blender moves it.
TEST_F(BlenderCharacter, APropParentedToABoneFollowsItAsInBlender) {
  std::ifstream in(dir_ / "truth_prop.json");
  const json prop = json::parse(in);
  for (const std::string file : {"character_prop.glb", "character_prop.fbx"}) {
    SCOPED_TRACE(file);
    const RiggedModel m = read_model(dir_ / file);
    ASSERT_EQ(m.parts.size(), 2u);
    EXPECT_NE(std::find_if(m.notes.begin(), m.notes.end(), [](const std::string& n) { return n.find("it follows joint \"hand\" rigidly") != std::string::npos; }),
              m.notes.end());
    double t0 = 0.0;
    const Similarity s = to_blender(m, file, "", t0);
    const ModelPart& part = m.parts[1];
    for (const auto& [frame, points] : prop["frames"].items()) {
      const double t = t0 + (std::stoi(frame) - 1) / truth_["fps"].get<double>();
      const Eigen::Matrix3Xd skin = s.affine() * skin_vertices(m, m.skeleton.world(sample(m.clips[0], m.skeleton, t)));
      EXPECT_LT(hausdorff(skin.middleCols(part.first_vertex, part.vertices), blender_points(points)), 1e-4) << "frame " << frame;
    }
  }
}

// The arm is smooth-shaded with a cylindrical UV map: each file's texture coordinates lie in the map's square
// (v up, as OBJ and USD have it: the arm's root at v = 0), and the normals computed from the skin's triangles,
// as every frame's are, agree with the normals Blender wrote.
TEST_F(BlenderCharacter, TextureCoordinatesAndNormalsAreReadAndNormalsFromTheTrianglesAgree) {
  for (const char* file : {"character.glb", "character.fbx", "character.dae"}) {
    SCOPED_TRACE(file);
    RiggedModel m = read_model(dir_ / file);
    (void)place_at_bind_pose(m);
    ASSERT_EQ(m.uv.cols(), m.vertices.cols());
    ASSERT_EQ(m.normals.cols(), m.vertices.cols());
    EXPECT_GE(m.uv.minCoeff(), -1e-6);
    EXPECT_LE(m.uv.maxCoeff(), 1.0 + 1e-6);
    // v grows along the arm (from its root at the origin): the lowest vertices have v near 0.
    Eigen::Index lowest = 0;
    for (Eigen::Index v = 0; v < m.vertices.cols(); ++v)
      if (m.vertices.col(v).norm() < m.vertices.col(lowest).norm()) lowest = v;
    EXPECT_LT(m.uv(1, lowest), 0.05) << "v runs down the image (glTF's v not flipped)?";
    const NormalGroups groups = normal_groups(m);
    const Eigen::Matrix3Xd ours = vertex_normals(m, groups, m.vertices);
    const Eigen::ArrayXd agree = (ours.array() * m.normals.array()).colwise().sum();
    // Angle-weighted normals, as Blender's: cos of the worst angle between them 0.99984 here (area weights gave 0.90).
    EXPECT_GT(agree.minCoeff(), 0.999) << "the worst vertex";
    EXPECT_GT(agree.mean(), 0.99999);
  }
}

// The hand in data/ (made elsewhere, from npm): the normals computed from its triangles agree with its own.
TEST(ModelNormals, TheHandsNormalsFromItsTrianglesAgreeWithItsOwn) {
  const RiggedModel m = read_model(fs::path(SNH_TESTS_DIR) / ".." / "data" / "hand" / "left.glb");
  ASSERT_EQ(m.normals.cols(), m.vertices.cols());
  ASSERT_EQ(m.uv.cols(), m.vertices.cols());
  const Eigen::Matrix3Xd ours = vertex_normals(m, normal_groups(m), m.vertices);
  const Eigen::ArrayXd agree = (ours.array() * m.normals.array()).colwise().sum();
  EXPECT_GT(agree.minCoeff(), 0.97);  // 0.977 (12°) at worst, where its tool weighted otherwise
  EXPECT_GT(agree.mean(), 0.999);
  // Inside out, the same normals (the sign follows the file's normals).
  RiggedModel flipped = m;
  flipped.triangles.row(1).swap(flipped.triangles.row(2));
  const Eigen::Matrix3Xd again = vertex_normals(flipped, normal_groups(flipped), flipped.vertices);
  EXPECT_LT((again - ours).cwiseAbs().maxCoeff(), 1e-12);
}

// A flesh run of the arm writes each frame's texture coordinates and normals into its OBJ frames and USD stage.
TEST_F(BlenderCharacter, FleshFramesAndStageCarryTextureCoordinatesAndNormals) {
  const fs::path out = fs::temp_directory_path() / ("snh-test-blender-flesh-" + std::to_string(::getpid()));
  std::string log;
  ASSERT_TRUE(run_flesh("character.glb", 3, out, log)) << log;
  const RiggedModel m = read_model(dir_ / "character.glb");
  std::ifstream in(out / "surface" / "003.obj");
  std::map<std::string, int> lines;
  std::string line, face;
  while (std::getline(in, line)) {
    const std::string tag = line.substr(0, line.find(' '));
    ++lines[tag];
    if (tag == "f" && face.empty()) face = line;
  }
  EXPECT_EQ(lines["v"], m.vertices.cols());
  EXPECT_EQ(lines["vt"], m.vertices.cols());
  EXPECT_EQ(lines["vn"], m.vertices.cols());
  EXPECT_EQ(lines["f"], m.triangles.cols());
  const int a = m.triangles(0, 0) + 1, b = m.triangles(1, 0) + 1, c = m.triangles(2, 0) + 1;
  EXPECT_EQ(face, fmt::format("f {}/{}/{} {}/{}/{} {}/{}/{}", a, a, a, b, b, b, c, c, c));
  int code = 0;
  const std::string checked = check_stage(out, 4, code);
  EXPECT_EQ(code, 0) << checked;
  EXPECT_NE(checked.find("flesh: " + std::to_string(m.triangles.cols()) + " faces"), std::string::npos) << checked;
  EXPECT_NE(checked.find("(extent, normals, primvars:st)"), std::string::npos) << checked;
  EXPECT_NE(checked.find("stage: metersPerUnit 1, upAxis Y"), std::string::npos) << checked;
  fs::remove_all(out);
}

// The stage of a character in centimetres, Z up (Blender's FBX with its own axes) says so.
TEST_F(BlenderCharacter, TheStageSaysTheFilesUnitAndUpAxis) {
  const fs::path out = fs::temp_directory_path() / ("snh-test-blender-zup-" + std::to_string(::getpid()));
  std::string log;
  ASSERT_TRUE(run_flesh("character_zup.fbx", 2, out, log)) << log;
  EXPECT_NE(log.find("model: units: the file says 1 unit = 1 cm"), std::string::npos) << log;
  int code = 0;
  const std::string checked = check_stage(out, 3, code);
  EXPECT_EQ(code, 0) << checked;
  EXPECT_NE(checked.find("stage: metersPerUnit 0.01, upAxis Z"), std::string::npos) << checked;
  std::ifstream stats_in(out / "stats.json");
  const json stats = json::parse(stats_in);
  EXPECT_EQ(stats["model_meters_per_unit"].get<double>(), 0.01);
  EXPECT_EQ(stats["model_up_axis"].get<std::string>(), "+Z");
  fs::remove_all(out);
}

/// The five rigged, animated characters of Debian's assimp-testmodels, read directly.
class AssimpTestModels : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kAssimpModels / "X" / "Testwuson.X")) GTEST_SKIP() << "assimp-testmodels is not installed";
  }
};

TEST_F(AssimpTestModels, EachCharacterIsReadWithItsJointsClipsAndMeshes) {
  struct Expect {
    const char* file;
    int joints, clips, parts;
    const char* clip;  // the clip played by default
    std::size_t notes;
    bool rest_is_bind;  // the file's rest pose is its bind pose, once the skin is in the right space
    double meters_per_unit;  // as the file says (FBX: UnitScaleFactor 1, centimetres, said in a note); .x: none
  };
  // huesitos' offsets are in its mesh node's frame (FBX), Testwuson's in the model's although its mesh node
  // turns a quarter (.x): read in the other space, each seemed bound in another pose, and Testwuson's first
  // frame failed. animation_with_skeleton is bound in another pose; anim_test's hierarchy lacks two bones.
  for (const Expect& e : {Expect{"FBX/huesitos.fbx", 10, 1, 1, "Armature|Action", 1, true, 0.01},
                          Expect{"FBX/animation_with_skeleton.fbx", 15, 1, 1, "Armature|ArmatureAction", 1, false, 0.01},
                          Expect{"X/Testwuson.X", 38, 3, 1, "Wuson_Run", 0, true, 1.0},
                          Expect{"X/BCN_Epileptic.X", 54, 1, 3, "Epileptisch", 0, true, 1.0},
                          // Its authors' note: the mesh names four bones, the hierarchy holds two.
                          Expect{"X/anim_test.x", 4, 1, 1, "cylinder_test", 2, false, 1.0}}) {
    SCOPED_TRACE(e.file);
    const RiggedModel m = read_model(kAssimpModels / e.file);
    EXPECT_EQ(m.skeleton.size(), e.joints);
    EXPECT_EQ(static_cast<int>(m.clips.size()), e.clips);
    EXPECT_EQ(static_cast<int>(m.parts.size()), e.parts);
    EXPECT_EQ(m.notes.size(), e.notes);
    EXPECT_EQ(m.meters_per_unit, e.meters_per_unit);
    EXPECT_EQ(m.up_axis, 1);  // all Y up
    EXPECT_EQ(m.up_sign, 1);
    ASSERT_GE(default_clip(m), 0);
    EXPECT_EQ(m.clips[static_cast<std::size_t>(default_clip(m))].name, e.clip);
    // Every vertex bound to real joints by weights summing to 1, and the skin at the bind pose where the file
    // put it (the rest pose of a .x file is often another pose).
    EXPECT_LT((m.joint_weight.colwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
    EXPECT_GE(m.joint_index.minCoeff(), 0);
    EXPECT_LT(m.joint_index.maxCoeff(), m.skeleton.size());
    RiggedModel placed = m;
    const BindPose bind = place_at_bind_pose(placed);
    EXPECT_EQ(bind.rest_is_bind, e.rest_is_bind) << bind.worst_joint << " by " << bind.worst_offset;
    const double size = (placed.vertices.rowwise().maxCoeff() - placed.vertices.rowwise().minCoeff()).norm();
    // (.x files store matrices and positions with 6 decimals: products of a few of them agree to about 1e-6.)
    EXPECT_LT((skin_vertices(placed, bind.joints) - placed.vertices).cwiseAbs().maxCoeff(), 1e-5 * size);
  }
}

TEST_F(AssimpTestModels, TheXFileClipsMoveTheSkin) {
  const RiggedModel m = read_model(kAssimpModels / "X" / "Testwuson.X");
  const Clip& run = m.clips[0];
  const Eigen::Matrix3Xd a = skin_vertices(m, m.skeleton.world(sample(run, m.skeleton, 0.0)));
  const Eigen::Matrix3Xd b = skin_vertices(m, m.skeleton.world(sample(run, m.skeleton, run.duration() / 2)));
  const double size = (m.vertices.rowwise().maxCoeff() - m.vertices.rowwise().minCoeff()).norm();
  EXPECT_GT((a - b).colwise().norm().maxCoeff(), 0.05 * size);
  EXPECT_FALSE(m.clips[2].moves());  // "Wuson_Bind": one pose
}

class AssimpErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snh-test-assimp-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  /// read_model(path) throws a RigError of one line that names the file and holds `fragment`.
  static void expect_error(const fs::path& path, const std::string& fragment) {
    test::expect_rig_error([](const fs::path& p) { return read_model(p); }, path, fragment);
  }
  void write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }
  fs::path dir_;
};

TEST_F(AssimpErrors, FilesItCannotUseAreRefusedInOneLine) {
  expect_error(dir_ / "missing.fbx", "no such file");
  fs::create_directories(dir_ / "folder.fbx");
  expect_error(dir_ / "folder.fbx", "a directory");
  write(dir_ / "empty.dae", "");
  expect_error(dir_ / "empty.dae", "empty file");
  write(dir_ / "junk.fbx", "this is not an FBX file\nat all\n");
  expect_error(dir_ / "junk.fbx", "assimp could not read it");
  // A well-formed model without bones: a triangle as OBJ.
  write(dir_ / "static.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  expect_error(dir_ / "static.obj", "no skinned mesh");
}

}  // namespace
}  // namespace snh
