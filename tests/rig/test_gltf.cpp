// glTF rigs: the WebXR generic hand (data/hand/left.glb: flat joints rebuilt into chains by name, bind
// pose consistent with its inverse bind matrices, a closed welded surface); a small rig written here as
// .gltf (embedded and external buffer) and .glb, whose joints, weights, welding and clips (LINEAR rotation,
// STEP translation, CUBICSPLINE scale) are checked against values worked out independently; and malformed
// files, each refused with one line naming the file.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/base64.hpp"
#include "rig_error.hpp"
#include "snh/rig/gltf.hpp"
#include "snh/rig/model.hpp"
#include "snh/rig/skinning.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

const fs::path kHand = fs::path(SNH_DATA_DIR) / "hand" / "left.glb";

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Every undirected edge of the triangles, with how many triangles share it.
std::map<std::pair<int, int>, int> edge_counts(const Eigen::Matrix3Xi& tris) {
  std::map<std::pair<int, int>, int> edges;
  for (Eigen::Index t = 0; t < tris.cols(); ++t)
    for (int c = 0; c < 3; ++c) {
      const int a = tris(c, t), b = tris((c + 1) % 3, t);
      ++edges[{std::min(a, b), std::max(a, b)}];
    }
  return edges;
}

bool closed(const Eigen::Matrix3Xi& tris) {
  for (const auto& [edge, count] : edge_counts(tris))
    if (count != 2) return false;
  return tris.cols() > 0;
}

Eigen::Matrix4d trs(const Eigen::Vector3d& t, const Eigen::Quaterniond& r, const Eigen::Vector3d& s) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r.toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

/// A glTF node's local matrix straight from its JSON (translation, rotation x y z w, scale; or matrix).
Eigen::Matrix4d node_matrix(const json& n) {
  if (n.contains("matrix")) {
    Eigen::Matrix4d m;
    for (int i = 0; i < 16; ++i) m(i % 4, i / 4) = n["matrix"][i].get<double>();
    return m;
  }
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), s = Eigen::Vector3d::Ones();
  Eigen::Quaterniond r = Eigen::Quaterniond::Identity();
  if (n.contains("translation")) t = Eigen::Vector3d(n["translation"][0], n["translation"][1], n["translation"][2]);
  if (n.contains("rotation")) r = Eigen::Quaterniond(n["rotation"][3], n["rotation"][0], n["rotation"][1], n["rotation"][2]);
  if (n.contains("scale")) s = Eigen::Vector3d(n["scale"][0], n["scale"][1], n["scale"][2]);
  return trs(t, r.normalized(), s);
}

// ---------------------------------------------------------------------------------------------------------
// The WebXR hand.

/// The hand, read once (a failure to read it fails each test that asks).
const RiggedModel& hand() {
  static const RiggedModel model = read_gltf(kHand);
  return model;
}

TEST(Hand, JointsAreRebuiltIntoFingerChainsByName) {
  const RiggedModel& m = hand();
  EXPECT_EQ(m.vertices.cols(), 1360);
  EXPECT_EQ(m.joint_index.cols(), 1360);
  ASSERT_EQ(m.skeleton.size(), 25);
  EXPECT_EQ(m.hierarchy, "names");
  EXPECT_TRUE(m.clips.empty());
  const Skeleton& s = m.skeleton;
  for (int j = 0; j < s.size(); ++j)
    EXPECT_EQ(s.joints[j].parent < 0, s.joints[j].name == "wrist") << s.joints[j].name << " is a root or should be";
  // Up from the tip of the index finger to the wrist.
  std::vector<std::string> chain;
  for (int j = s.find("index-finger-tip"), steps = 0; j >= 0 && steps < 30; j = s.joints[j].parent, ++steps)
    chain.push_back(s.joints[j].name);
  EXPECT_EQ(chain, (std::vector<std::string>{"index-finger-tip", "index-finger-phalanx-distal",
                                             "index-finger-phalanx-intermediate", "index-finger-phalanx-proximal",
                                             "index-finger-metacarpal", "wrist"}));
  EXPECT_EQ(s.joints[s.find("thumb-phalanx-distal")].parent, s.find("thumb-phalanx-proximal"));
  const auto children = s.children();
  for (int j = 0; j < s.size(); ++j) {
    const std::string& n = s.joints[j].name;
    const std::size_t expected = n == "wrist" ? 5 : n.ends_with("-tip") ? 0 : 1;
    EXPECT_EQ(children[j].size(), expected) << n;
  }
}

TEST(Hand, RestPoseKeepsTheFilesJointPlacesAndMatchesTheInverseBinds) {
  const RiggedModel& m = hand();
  // The joints' places in the file: their nodes' transforms below their parent node ("Armature").
  const std::string bytes = read_bytes(kHand);
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  const json doc = json::parse(bytes.substr(20, length));
  std::vector<int> parent(doc["nodes"].size(), -1);
  for (std::size_t i = 0; i < doc["nodes"].size(); ++i)
    for (const int c : doc["nodes"][i].value("children", std::vector<int>{})) parent[c] = static_cast<int>(i);
  const auto world = m.skeleton.world(m.skeleton.rest_pose());
  for (std::size_t i = 0; i < doc["nodes"].size(); ++i) {
    const int j = m.skeleton.find(doc["nodes"][i].value("name", ""));
    if (j < 0) continue;
    Eigen::Matrix4d w = node_matrix(doc["nodes"][i]);
    for (int p = parent[i]; p >= 0; p = parent[p]) w = node_matrix(doc["nodes"][p]) * w;
    // The file's scales differ from 1 by float32 rounding; rebuilding drops that much shear.
    EXPECT_LT((world[j].matrix() - w).cwiseAbs().maxCoeff(), 1e-6) << m.skeleton.joints[j].name;
  }
  // world · inverse bind ≈ identity: both are float32 data of a 10 cm hand, so agree to about 1e-6.
  ASSERT_EQ(m.inverse_bind.size(), 25u);
  for (int j = 0; j < 25; ++j)
    EXPECT_LT((world[j].matrix() * m.inverse_bind[j] - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-5)
        << m.skeleton.joints[j].name;
  // Skinned at rest, every vertex stays where it is.
  EXPECT_LT((skin_vertices(m, world) - m.vertices).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(Hand, WeldedSurfaceIsClosed) {
  const RiggedModel& m = hand();
  ASSERT_EQ(m.weld.size(), 1360u);
  for (std::size_t v = 0; v < m.weld.size(); ++v) {
    ASSERT_GE(m.weld[v], 0);
    ASSERT_LT(m.weld[v], m.surface_vertices.cols());
    ASSERT_EQ(m.surface_vertices.col(m.weld[v]), m.vertices.col(static_cast<Eigen::Index>(v)));
  }
  for (Eigen::Index i = 0; i < m.vertices.cols(); ++i)
    EXPECT_NEAR(m.joint_weight.col(i).sum(), 1.0, 1e-12);
  EXPECT_TRUE(closed(m.surface_triangles));
  EXPECT_FALSE(closed(m.triangles)) << "the render mesh has seams";
  // Consistently oriented (each directed edge once) and counter-clockwise seen from outside (positive volume).
  std::map<std::pair<int, int>, int> directed;
  double volume = 0;
  for (Eigen::Index t = 0; t < m.surface_triangles.cols(); ++t) {
    const Eigen::Vector3i f = m.surface_triangles.col(t);
    for (int c = 0; c < 3; ++c) ++directed[{f(c), f((c + 1) % 3)}];
    volume += m.surface_vertices.col(f(0)).dot(m.surface_vertices.col(f(1)).cross(m.surface_vertices.col(f(2)))) / 6;
  }
  for (const auto& [edge, count] : directed) EXPECT_EQ(count, 1) << edge.first << " → " << edge.second;
  EXPECT_GT(volume, 0.0);
  // Euler characteristic V − E + F of the welded surface (2 for a sphere).
  const auto euler = m.surface_vertices.cols() - static_cast<Eigen::Index>(edge_counts(m.surface_triangles).size()) +
                     m.surface_triangles.cols();
  std::printf("hand: %ld vertices, %ld triangles; welded %ld vertices, %ld triangles, Euler characteristic %ld, "
              "volume %.1f cm^3\n",
              static_cast<long>(m.vertices.cols()), static_cast<long>(m.triangles.cols()),
              static_cast<long>(m.surface_vertices.cols()), static_cast<long>(m.surface_triangles.cols()),
              static_cast<long>(euler), volume * 1e6);
  RecordProperty("welded_vertices", static_cast<int>(m.surface_vertices.cols()));
  RecordProperty("welded_triangles", static_cast<int>(m.surface_triangles.cols()));
  EXPECT_EQ(euler, 2);
}

TEST(Hand, HasNoClipToFind) {
  try {
    (void)find_clip(hand(), "0");
    ADD_FAILURE() << "found a clip";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("left.glb: no animation clip \"0\" (the model has no animation clip)"),
              std::string::npos)
        << e.what();
  }
}

// ---------------------------------------------------------------------------------------------------------
// A small rig written here: a tetrahedron (a seam and a triangle that collapses when welded) on a hip, knee
// and ankle below an "Armature" node that turns, moves and doubles them.

const Eigen::Vector3d kX = Eigen::Vector3d::UnitX(), kY = Eigen::Vector3d::UnitY(), kZ = Eigen::Vector3d::UnitZ();
using test::about;

const Eigen::Matrix4d kArmature = trs({0.1, 0.2, 0.3}, about(kY, 0.7), {2, 2, 2});
const Eigen::Matrix4d kHip = trs({0, 0.5, 0}, about(kZ, 0.2), {1, 1, 1});
const Eigen::Matrix4d kKnee = trs({0, 1, 0}, about(kX, 0.5), {1, 1, 1});
const Eigen::Matrix4d kAnkle = trs({0, 1, 0}, Eigen::Quaterniond::Identity(), {1.2, 1.2, 1.2});  // written as a matrix

// The clip "walk": the knee turns about x through these angles (LINEAR), the hip steps (STEP), the ankle's scale
// follows c · p(t) (CUBICSPLINE, tangents p'); a second, unnamed clip turns the hip.
const std::vector<double> kRotTimes{0, 1, 2}, kAngles{0.5, 1.5, -0.5};
const std::vector<double> kStepTimes{0, 0.5, 1.5};
const std::vector<Eigen::Vector3d> kSteps{{0, 0.5, 0}, {0.3, 0.5, 0}, {0.3, 0.9, -0.2}};
const std::vector<double> kCubicTimes{0, 0.5, 2};
const Eigen::Vector3d kCubicScale(1, 1.1, 0.9);
double p(double t) { return 1.2 + 0.3 * t - 0.4 * t * t + 0.15 * t * t * t; }
double dp(double t) { return 0.3 - 0.8 * t + 0.45 * t * t; }

/// Buffer bytes with their views and accessors.
struct Blob {
  std::string bytes;
  json views = json::array(), accessors = json::array();
  template <class T>
  int add(const std::vector<T>& data, int component, const char* type, std::size_t count, bool normalized = false) {
    while (bytes.size() % 4) bytes.push_back('\0');
    const std::size_t offset = bytes.size();
    bytes.append(reinterpret_cast<const char*>(data.data()), data.size() * sizeof(T));
    views.push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", data.size() * sizeof(T)}});
    json a = {{"bufferView", views.size() - 1}, {"componentType", component}, {"type", type}, {"count", count}};
    if (normalized) a["normalized"] = true;
    accessors.push_back(a);
    return static_cast<int>(accessors.size()) - 1;
  }
};

std::vector<float> floats(std::initializer_list<double> v) { return std::vector<float>(v.begin(), v.end()); }
void push(std::vector<float>& out, const Eigen::Quaterniond& q) {
  for (const double x : {q.x(), q.y(), q.z(), q.w()}) out.push_back(static_cast<float>(x));
}
void push(std::vector<float>& out, const Eigen::Vector3d& v) {
  for (const double x : {v.x(), v.y(), v.z()}) out.push_back(static_cast<float>(x));
}

constexpr int kFloat = 5126, kUByte = 5121, kUShort = 5123;

struct Synth {
  // Primitive 0 (indexed, float weights): the tetrahedron's corners, vertex 4 a seam copy of vertex 0; the
  // last triangle (0, 4, 1) collapses when welded. Joints: 0 ankle, 1 hip, 2 knee (the skin's order).
  std::vector<float> pos0 = floats({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0});
  std::vector<std::uint8_t> joints0{1, 0, 0, 0, 1, 2, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0};
  std::vector<float> weights0 = floats({1, 0, 0, 0, 0.25, 0.25, 0, 0, 0.7, 0.3, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0});
  std::vector<std::uint16_t> indices0{0, 2, 1, 4, 1, 3, 0, 3, 2, 0, 4, 1};
  // Primitive 1 (not indexed, unsigned short joints, normalized unsigned byte weights): the face (1, 2, 3).
  std::vector<float> pos1 = floats({1, 0, 0, 0, 1, 0, 0, 0, 1});
  std::vector<std::uint16_t> joints1{2, 0, 0, 0, 0, 0, 0, 0, 1, 2, 0, 0};
  std::vector<std::uint8_t> weights1{200, 100, 0, 0, 255, 0, 0, 0, 51, 204, 0, 0};
  std::vector<float> rot_times = floats({0, 1, 2});
  int mode = 4;
  bool skinned = true;
  std::size_t pos0_count = 5;  ///< the POSITION accessor's count
  bool hip_has_two_parents = false;
  double armature_scale_z = 2;  ///< not 2: the hip (turned about z) would need a non-uniform scale folded into its keys
  /// The ankle's inverse bind matrix: its 3x3 part scaled by this, and its last row (0 0 0 1) replaced by
  /// (0 0 ibm_projective 1) where that is not 0.
  double ibm_scale = 1, ibm_projective = 0;
  std::function<void(json&)> patch;  ///< applied to the finished document

  json document(Blob& b) const {
    // Inverse bind matrices: the joints' world transforms at rest, inverted.
    const Eigen::Matrix4d hip = kArmature * kHip, knee = hip * kKnee, ankle = knee * kAnkle;
    std::vector<float> ib;
    for (const Eigen::Matrix4d* w : {&ankle, &hip, &knee}) {
      Eigen::Matrix4d inv = w->inverse();
      if (w == &ankle) {
        inv.topLeftCorner<3, 3>() *= ibm_scale;
        inv(3, 2) = ibm_projective;
      }
      for (int i = 0; i < 16; ++i) ib.push_back(static_cast<float>(inv(i % 4, i / 4)));
    }
    json prim0 = {{"attributes", {{"POSITION", b.add(pos0, kFloat, "VEC3", pos0_count)},
                                  {"JOINTS_0", b.add(joints0, kUByte, "VEC4", 5)},
                                  {"WEIGHTS_0", b.add(weights0, kFloat, "VEC4", 5)}}},
                  {"indices", b.add(indices0, kUShort, "SCALAR", indices0.size())},
                  {"mode", mode}};
    json prim1 = {{"attributes", {{"POSITION", b.add(pos1, kFloat, "VEC3", 3)},
                                  {"NORMAL", b.add(pos1, kFloat, "VEC3", 3)},
                                  {"JOINTS_0", b.add(joints1, kUShort, "VEC4", 3)},
                                  {"WEIGHTS_0", b.add(weights1, kUByte, "VEC4", 3, true)}}}};
    const int ibm = b.add(ib, kFloat, "MAT4", 3);

    std::vector<float> rot_values, step_values, cubic_values, run_values;
    for (std::size_t k = 0; k < kAngles.size(); ++k) {
      const Eigen::Quaterniond q = about(kX, kAngles[k]);
      push(rot_values, k == 2 ? Eigen::Quaterniond(-q.coeffs()) : q);  // q and −q are the same rotation
    }
    for (const auto& v : kSteps) push(step_values, v);
    for (const double t : kCubicTimes)
      for (const double f : {dp(t), p(t), dp(t)}) push(cubic_values, Eigen::Vector3d(f * kCubicScale));
    push(run_values, about(kZ, 0.2));
    push(run_values, about(kZ, 1.2));
    const std::vector<float> step_times(kStepTimes.begin(), kStepTimes.end()), cubic_times(kCubicTimes.begin(), kCubicTimes.end());
    json walk_samplers = json::array({
        {{"input", b.add(rot_times, kFloat, "SCALAR", rot_times.size())}, {"output", b.add(rot_values, kFloat, "VEC4", 3)}},
        {{"input", b.add(step_times, kFloat, "SCALAR", 3)}, {"output", b.add(step_values, kFloat, "VEC3", 3)}, {"interpolation", "STEP"}},
        {{"input", b.add(cubic_times, kFloat, "SCALAR", 3)}, {"output", b.add(cubic_values, kFloat, "VEC3", 9)},
         {"interpolation", "CUBICSPLINE"}},
    });
    json walk_channels = json::array({
        {{"sampler", 0}, {"target", {{"node", 3}, {"path", "rotation"}}}},
        {{"sampler", 1}, {"target", {{"node", 2}, {"path", "translation"}}}},
        {{"sampler", 2}, {"target", {{"node", 4}, {"path", "scale"}}}},
        {{"sampler", 1}, {"target", {{"node", 1}, {"path", "translation"}}}},  // the mesh node: not a joint
        {{"sampler", 0}, {"target", {{"node", 3}, {"path", "weights"}}}},      // morph weights: not a transform
    });
    const std::vector<float> run_times{0, 4};
    json run = {{"samplers", json::array({{{"input", b.add(run_times, kFloat, "SCALAR", 2)},
                                           {"output", b.add(run_values, kFloat, "VEC4", 2)}}})},
                {"channels", json::array({{{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}}})}};

    const auto node = [](const char* name, const Eigen::Vector3d& t, const Eigen::Quaterniond& r, double s) {
      return json{{"name", name}, {"translation", {t.x(), t.y(), t.z()}}, {"rotation", {r.x(), r.y(), r.z(), r.w()}},
                  {"scale", {s, s, s}}};
    };
    json nodes = json::array();
    nodes.push_back(node("Armature", {0.1, 0.2, 0.3}, about(kY, 0.7), 2));
    nodes[0]["children"] = {1, 2};
    nodes[0]["scale"][2] = armature_scale_z;
    nodes.push_back({{"name", "body"}, {"mesh", 0}, {"translation", {5, 5, 5}}});
    if (skinned) nodes[1]["skin"] = 0;
    nodes.push_back(node("hip", {0, 0.5, 0}, about(kZ, 0.2), 1));
    nodes[2]["children"] = {3};
    nodes.push_back(node("knee", {0, 1, 0}, about(kX, 0.5), 1));
    nodes[3]["children"] = hip_has_two_parents ? json::array({4, 2}) : json::array({4});
    json ankle_matrix = json::array();
    for (int i = 0; i < 16; ++i) ankle_matrix.push_back(kAnkle(i % 4, i / 4));
    nodes.push_back({{"name", "ankle"}, {"matrix", ankle_matrix}});

    json doc = {{"asset", {{"version", "2.0"}}},
            {"scene", 0},
            {"scenes", json::array({{{"nodes", json::array({0})}}})},
            {"nodes", nodes},
            {"meshes", json::array({{{"primitives", {prim0, prim1}}}})},
            {"skins", json::array({{{"joints", {4, 2, 3}}, {"inverseBindMatrices", ibm}}})},
            {"animations", json::array({{{"name", "walk"}, {"samplers", walk_samplers}, {"channels", walk_channels}}, run})},
            {"accessors", b.accessors},
            {"bufferViews", b.views}};
    if (patch) patch(doc);
    return doc;
  }
};

enum class Container { embedded, external, binary };

fs::path write(const fs::path& dir, const std::string& stem, const Synth& synth, Container how) {
  Blob b;
  json doc = synth.document(b);
  const fs::path path = dir / (stem + (how == Container::binary ? ".glb" : ".gltf"));
  json buffer = {{"byteLength", b.bytes.size()}};
  if (how == Container::embedded)
    buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(b.bytes.data(), b.bytes.size());
  if (how == Container::external) {
    buffer["uri"] = stem + ".bin";
    std::ofstream(dir / (stem + ".bin"), std::ios::binary) << b.bytes;
  }
  doc["buffers"] = json::array({buffer});
  std::ofstream out(path, std::ios::binary);
  if (how != Container::binary) {
    out << doc.dump(1);
    return path;
  }
  // GLB: a 12-byte header, a JSON chunk padded with spaces, a BIN chunk padded with zeros (glTF 2.0 §4.4).
  std::string text = doc.dump(), bin = b.bytes;
  while (text.size() % 4) text += ' ';
  while (bin.size() % 4) bin.push_back('\0');
  const auto u32 = [&](std::uint32_t v) { out.write(reinterpret_cast<const char*>(&v), 4); };
  out << "glTF";
  u32(2);
  u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
  u32(static_cast<std::uint32_t>(text.size()));
  u32(0x4E4F534Au);  // "JSON"
  out << text;
  u32(static_cast<std::uint32_t>(bin.size()));
  u32(0x004E4942u);  // "BIN\0"
  out << bin;
  return path;
}

class Gltf : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("snh_test_gltf_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// read_gltf(path) throws a RigError whose message is one line naming the file and containing `fragment`.
  void refuses(const fs::path& path, const std::string& fragment) {
    test::expect_rig_error([](const fs::path& p) { return read_gltf(p); }, path, fragment);
  }
  fs::path dir_;
};

/// The world transforms of (ankle, hip, knee) at time t of "walk", composed here from the keys.
std::vector<Eigen::Matrix4d> walk_world(double t) {
  const auto clamp = [](double v, double lo, double hi) { return std::min(std::max(v, lo), hi); };
  const double tr = clamp(t, 0, 2);
  const double angle = tr <= 1 ? kAngles[0] + tr * (kAngles[1] - kAngles[0]) : kAngles[1] + (tr - 1) * (kAngles[2] - kAngles[1]);
  const Eigen::Vector3d step = t < kStepTimes[1] ? kSteps[0] : t < kStepTimes[2] ? kSteps[1] : kSteps[2];
  const Eigen::Vector3d scale = p(clamp(t, 0, 2)) * kCubicScale;
  const Eigen::Matrix4d hip = kArmature * trs(step, about(kZ, 0.2), Eigen::Vector3d::Ones());
  const Eigen::Matrix4d knee = hip * trs({0, 1, 0}, about(kX, angle), Eigen::Vector3d::Ones());
  const Eigen::Matrix4d ankle = knee * trs({0, 1, 0}, Eigen::Quaterniond::Identity(), scale);
  return {ankle, hip, knee};
}

void expect_synth(const RiggedModel& m) {
  // Mesh: both primitives, in the file's order; the mesh node's own transform ignored (glTF 2.0 §3.7.3.3).
  ASSERT_EQ(m.vertices.cols(), 8);
  ASSERT_EQ(m.triangles.cols(), 5);
  EXPECT_EQ(m.vertices.col(1), Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(m.vertices.col(7), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(m.triangles.col(1), Eigen::Vector3i(4, 1, 3));
  EXPECT_EQ(m.triangles.col(4), Eigen::Vector3i(5, 6, 7));
  EXPECT_EQ(m.weld, (std::vector<int>{0, 1, 2, 3, 0, 1, 2, 3}));
  EXPECT_EQ(m.surface_vertices.cols(), 4);
  EXPECT_EQ(m.surface_triangles.cols(), 4);  // (0, 4, 1) collapsed
  EXPECT_TRUE(closed(m.surface_triangles));
  // Weights normalized: 0.25/0.25 → 0.5/0.5; unsigned bytes 200/100 of 255 → 2/3, 1/3; 51/204 → 0.2/0.8.
  EXPECT_EQ(m.joint_index.col(1), Eigen::Vector4i(1, 2, 0, 0));
  EXPECT_NEAR(m.joint_weight(0, 1), 0.5, 1e-7);
  EXPECT_NEAR(m.joint_weight(1, 1), 0.5, 1e-7);
  EXPECT_EQ(m.joint_index.col(5), Eigen::Vector4i(2, 0, 0, 0));
  EXPECT_NEAR(m.joint_weight(0, 5), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(m.joint_weight(1, 5), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(m.joint_weight(0, 7), 0.2, 1e-12);
  EXPECT_NEAR(m.joint_weight(1, 7), 0.8, 1e-12);
  // Skeleton in the skin's order (ankle, hip, knee): parents after children; the hip's rest folds in the Armature.
  EXPECT_EQ(m.hierarchy, "file");
  ASSERT_EQ(m.skeleton.size(), 3);
  EXPECT_EQ(m.skeleton.joints[0].name, "ankle");
  EXPECT_EQ(m.skeleton.joints[0].parent, 2);
  EXPECT_EQ(m.skeleton.joints[1].parent, -1);
  EXPECT_EQ(m.skeleton.joints[2].parent, 1);
  EXPECT_LT((m.skeleton.joints[1].rest.matrix().matrix() - kArmature * kHip).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((m.skeleton.joints[2].rest.matrix().matrix() - kKnee).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((m.skeleton.joints[0].rest.matrix().matrix() - kAnkle).cwiseAbs().maxCoeff(), 1e-14);
  const auto rest = m.skeleton.world(m.skeleton.rest_pose());
  ASSERT_EQ(m.inverse_bind.size(), 3u);
  for (int j = 0; j < 3; ++j)  // float32 inverse binds of transforms of size about 2
    EXPECT_LT((rest[j].matrix() * m.inverse_bind[j] - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-6) << j;
  EXPECT_LT((skin_vertices(m, rest) - m.vertices).cwiseAbs().maxCoeff(), 1e-6);

  // Clips: "walk" keeps its three joint channels; the second is named by its index.
  ASSERT_EQ(m.clips.size(), 2u);
  const Clip& walk = find_clip(m, "walk");
  EXPECT_EQ(&find_clip(m, "0"), &walk);
  EXPECT_EQ(find_clip(m, "1").name, "animation1");
  EXPECT_DOUBLE_EQ(walk.duration(), 2.0);
  EXPECT_DOUBLE_EQ(m.clips[1].duration(), 4.0);
  ASSERT_EQ(walk.channels.size(), 3u);
  EXPECT_EQ(walk.channels[0].interpolation, Interpolation::linear);
  EXPECT_EQ(walk.channels[0].path, ChannelPath::rotation);
  EXPECT_EQ(walk.channels[0].joint, 2);
  EXPECT_EQ(walk.channels[0].times, kRotTimes);
  EXPECT_EQ(walk.channels[1].interpolation, Interpolation::step);
  EXPECT_EQ(walk.channels[2].interpolation, Interpolation::cubic_spline);
  EXPECT_EQ(walk.channels[2].values.cols(), 9);
  for (const double t : {-1.0, 0.0, 0.2, 0.5, 0.75, 1.0, 1.25, 1.5, 1.9, 2.0, 3.0}) {
    const auto world = m.skeleton.world(sample(walk, m.skeleton, t));
    const auto expected = walk_world(t);
    for (int j = 0; j < 3; ++j)  // keys stored as float32
      EXPECT_LT((world[j].matrix() - expected[j]).cwiseAbs().maxCoeff(), 1e-6) << "t = " << t << ", joint " << j;
  }
  // The second clip turns the hip about z from 0.2 to 1.2 in 4 s (below the Armature's turn).
  const auto world = m.skeleton.world(sample(m.clips[1], m.skeleton, 1.0));
  EXPECT_LT((world[1].matrix() - kArmature * trs({0, 0.5, 0}, about(kZ, 0.45), Eigen::Vector3d::Ones())).cwiseAbs().maxCoeff(),
            1e-6);
}

TEST_F(Gltf, EmbeddedExternalAndBinaryBuffersReadTheSame) {
  for (const auto how : {Container::embedded, Container::external, Container::binary}) {
    SCOPED_TRACE(static_cast<int>(how));
    const fs::path path = write(dir_, "rig", Synth{}, how);
    const RiggedModel m = read_gltf(path);
    EXPECT_EQ(m.source, path);
    expect_synth(m);
  }
}

TEST_F(Gltf, UnknownClipsAreListed) {
  const RiggedModel m = read_gltf(write(dir_, "rig", Synth{}, Container::binary));
  for (const std::string name : {"run", "2", ""}) {
    try {
      (void)find_clip(m, name);
      ADD_FAILURE() << name;
    } catch (const RigError& e) {
      EXPECT_EQ(std::string(e.what()), (dir_ / "rig.glb").string() + ": no animation clip \"" + name + "\" (clips: walk, animation1)");
    }
  }
}

TEST_F(Gltf, MalformedFilesAreRefusedInOneLine) {
  const auto text = [&](const std::string& name, const std::string& content) {
    std::ofstream(dir_ / name, std::ios::binary) << content;
    return dir_ / name;
  };
  refuses(dir_ / "missing.glb", "no such file");
  refuses(text("notes.gltf", "these are not the droids\n"), "not glTF");
  refuses(text("notes.glb", "these are not the droids\n"), "not a glTF binary");
  refuses(text("object.gltf", "{\"hello\": 1}"), "not a valid glTF file");
  refuses(text("empty.glb", ""), "empty");
  const fs::path huge = text("huge.glb", "glTF");
  fs::resize_file(huge, (std::uintmax_t{1} << 30) + 1);  // sparse: refused before it is read
  refuses(huge, "too large");
  fs::create_directories(dir_ / "folder.gltf");
  refuses(dir_ / "folder.gltf", "directory");
  const std::string hand = read_bytes(kHand);
  refuses(text("half.glb", hand.substr(0, hand.size() / 2)), "not a valid glTF binary");
  refuses(text("header.glb", hand.substr(0, 30)), "not a valid glTF binary");
  // JSON nested 20 000 deep (40 KB) overflowed tinygltf's recursion: measured first and refused, as text and
  // as a GLB's JSON chunk; 64 levels pass the check (and fail later, for what they lack).
  const std::string deep = std::string(20000, '[') + std::string(20000, ']');
  refuses(text("deep.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + deep + "}"), "nested deeper than 64 levels");
  std::string chunk = "{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + deep + "}";
  while (chunk.size() % 4) chunk += ' ';
  const auto u32 = [](std::uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  refuses(text("deep.glb", "glTF" + u32(2) + u32(static_cast<std::uint32_t>(20 + chunk.size())) +
                               u32(static_cast<std::uint32_t>(chunk.size())) + "JSON" + chunk),
          "nested deeper than 64 levels");
  refuses(text("shallow.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"extras\": " + std::string(62, '[') + std::string(62, ']') + "}"),
          "no skinned mesh");

  const auto variant = [&](const std::string& stem, auto change) {
    Synth s;
    change(s);
    return write(dir_, stem, s, Container::embedded);
  };
  refuses(variant("no_skin", [](Synth& s) { s.skinned = false; }), "no skinned mesh (a mesh node with a skin)");
  refuses(variant("lines", [](Synth& s) { s.mode = 1; }), "mesh 0 primitive 0: mode 1 is not triangles");
  refuses(variant("joint", [](Synth& s) { s.joints0[4 * 3 + 1] = 3; }), "vertex 3 is bound to joint 3, but the skin has 3 joints");
  refuses(variant("huge", [](Synth& s) { s.pos0[7] = 3e38f; }), "vertex 2 has a coordinate of 3e+38, beyond 1e+12");
  refuses(variant("nan", [](Synth& s) { s.pos0[7] = std::numeric_limits<float>::quiet_NaN(); }),
          "vertex 2 has a position that is not finite");
  refuses(variant("times", [](Synth& s) { s.rot_times = floats({0, 1, 1}); }), "not strictly increasing");
  // Values that used to be taken and gave wrong frames (issue 32): refused, each naming what is wrong.
  refuses(variant("ibm_zero", [](Synth& s) { s.ibm_scale = 0; }), "\"ankle\" (skin 0) is singular");
  refuses(variant("ibm_tiny", [](Synth& s) { s.ibm_scale = 1e-30; }), "is singular or scales by");
  refuses(variant("ibm_projective", [](Synth& s) { s.ibm_projective = 0.5; }), "is projective");
  refuses(variant("far", [](Synth& s) { s.patch = [](json& d) { d["nodes"][2]["translation"][0] = 1e300; }; }),
          "\"hip\" has a translation of 1e+300, beyond 1e+12");
  refuses(variant("early", [](Synth& s) { s.rot_times = floats({-1, 1, 2}); }), "key time 0 is negative");
  refuses(variant("draco", [](Synth& s) { s.patch = [](json& d) { d["extensionsRequired"] = {"KHR_draco_mesh_compression"}; }; }),
          "requires the extension KHR_draco_mesh_compression, which snh does not read");
  refuses(variant("scene", [](Synth& s) { s.patch = [](json& d) { d["scene"] = 3; }; }), "its scene is 3, but it has 1 scenes");
  refuses(variant("version", [](Synth& s) { s.patch = [](json& d) { d["asset"]["version"] = "3.0"; }; }),
          "asset version \"3.0\": snh reads glTF 2.0");
  {  // A GLB whose header says version 1.
    std::string glb = read_bytes(write(dir_, "v1", Synth{}, Container::binary));
    glb[4] = 1;
    refuses(text("v1.glb", glb), "a glTF binary of version 1: snh reads version 2");
  }
  // Names with control characters (ESC, BEL, a newline) are read with them written as \xNN, so that they
  // print as they are instead of acting on the terminal.
  const RiggedModel named = read_model(variant("names", [](Synth& s) {
    s.patch = [](json& d) {
      d["nodes"][2]["name"] = "hip\x1b[31m\n";
      d["animations"][0]["name"] = std::string("walk\x07\0", 6);
    };
  }));
  EXPECT_EQ(named.skeleton.joints[static_cast<std::size_t>(named.skeleton.find("hip\\x1b[31m\\x0a"))].name, "hip\\x1b[31m\\x0a");
  EXPECT_EQ(named.clips[0].name, "walk\\x07\\x00");
  // Extensions that change no vertex (materials) do not stop a model.
  EXPECT_NO_THROW((void)read_gltf(variant("materials", [](Synth& s) {
    s.patch = [](json& d) { d["extensionsRequired"] = {"KHR_materials_unlit"}; d["extensionsUsed"] = {"KHR_materials_unlit"}; };
  })));
  refuses(variant("weights", [](Synth& s) { std::fill(s.weights0.begin() + 8, s.weights0.begin() + 12, 0.0f); }),
          "vertex 2 has joint weights that are all zero");
  refuses(variant("index", [](Synth& s) { s.indices0[5] = 5; }), "index 5 refers to vertex 5");
  refuses(variant("overrun", [](Synth& s) { s.pos0_count = 6; }), "overrun buffer view");
  refuses(variant("parents", [](Synth& s) { s.hip_has_two_parents = true; }), "node 2 is a child of two nodes");
  refuses(variant("stretch", [](Synth& s) { s.armature_scale_z = 3; }),
          "joint \"hip\" is animated below nodes whose transforms scale non-uniformly");
  const fs::path external = write(dir_, "lost", Synth{}, Container::external);
  fs::remove(dir_ / "lost.bin");
  refuses(external, "not a valid glTF file");
  // The files a glTF names are checked as the model is: a FIFO (which would block the open forever), a link to
  // one, and a buffer over 1 GiB are refused at once, without being read.
  ASSERT_EQ(::mkfifo((dir_ / "lost.bin").c_str(), 0600), 0);
  refuses(external, "lost.bin: not a regular file");
  fs::remove(dir_ / "lost.bin");
  ASSERT_EQ(::mkfifo((dir_ / "fifo.bin").c_str(), 0600), 0);
  fs::create_symlink(dir_ / "fifo.bin", dir_ / "lost.bin");
  refuses(external, "lost.bin: not a regular file");
  fs::remove(dir_ / "lost.bin");
  fs::create_directories(dir_ / "lost.bin");  // said "std::bad_alloc" before
  refuses(external, "lost.bin: a directory");
  fs::remove(dir_ / "lost.bin");
  std::ofstream(dir_ / "lost.bin").put('\0');
  fs::resize_file(dir_ / "lost.bin", (std::uintmax_t{1} << 30) + 1);  // sparse
  refuses(external, "lost.bin: too large");
  // A buffer's file of another size than its byteLength is refused without being read (900 MB were read whole
  // before tinygltf's "File size mismatch").
  fs::resize_file(dir_ / "lost.bin", std::uintmax_t{900} << 20);
  refuses(external, "lost.bin: 943718400 bytes, where the glTF's buffer says");
  // A GLB is measured by its header first: bytes after its end, or a file of zeros named .glb, are refused
  // without reading the rest.
  const fs::path padded = text("padded.glb", hand);
  fs::resize_file(padded, hand.size() + (std::uintmax_t{1} << 28));
  refuses(padded, fmt::format("its header says {} bytes, the file has {}", hand.size(), hand.size() + (std::uintmax_t{1} << 28)));
  const fs::path zeros = text("zeros.glb", std::string(16, '\0'));
  fs::resize_file(zeros, std::uintmax_t{1} << 28);
  refuses(zeros, "not a glTF binary (it does not start with \"glTF\")");
}

}  // namespace
}  // namespace snh
