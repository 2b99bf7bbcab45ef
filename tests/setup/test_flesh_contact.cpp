// Flesh with contact on its render surface (the WebXR hand closing into a fist, scenes/hand_fist.json, the
// whole clip: the fingers close, then the wrist turns with the fist closed): with self-contact no two triangles
// of the welded render surface intersect at any frame (the brute-force test of tests/contact/surface_checks.hpp
// over the whole surface), and with the bones' capsules as colliders no skin point they act on enters one;
// without contact both happen. The contact statistics: pairs in range and a smallest distance within
// (0, d̂) with contact, no contact fields without. The bones' colliders: which skin points each acts on.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "contact/surface_checks.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/rig/gltf.hpp"
#include "snh/fem/collider_term.hpp"
#include "snh/math/union_find.hpp"
#include "snh/setup/flesh.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct FistRun {
  BuiltScene scene;
  SceneResult result;
  std::string log;
  json stats;
  int frames_intersecting = 0;
  int first_intersecting = -1;
  /// The smallest distance outside a bone's capsule, at any frame, of the skin points its collider acts on
  /// (bone_collider_points; negative: inside).
  double capsule_clearance = INFINITY;
  int frames_written = 0;
};

/// The fist (36 frames to t = 3) at the scene's lattice resolution 24, with or without self-contact (and
/// with it the bones' capsules).
FistRun run_fist(bool self_contact, const fs::path& out) {
  const fs::path file = fs::path(SNH_SOURCE_DIR) / "scenes" / "hand_fist.json";
  std::ifstream in(file);
  json j = json::parse(in);
  j["output"] = {{"dir", out.string()}};
  if (self_contact) j["contact"] = {{"self", true}, {"bones", true}};
  FistRun run;
  run.scene = build_scene(parse_scene(j, file));
  std::ostringstream log;
  run.result = run_scene(run.scene, log);
  run.log = log.str();
  std::ifstream st(out / "stats.json");
  run.stats = json::parse(st);
  // Every frame's render surface (model order), welded, checked for intersecting triangles.
  const Flesh& flesh = *run.scene.body->flesh;
  const RiggedModel& m = flesh.model;
  const double dhat = self_contact ? run.stats.at("contact").at("dhat").get<double>() : flesh_contact_dhat(flesh);
  const std::vector<std::vector<int>> colliding = bone_collider_points(flesh, dhat);
  const int frames = j.at("frames").get<int>();
  // The frames that converged (a failed last frame is written too, at its partial state: issue 32).
  for (int f = 0; f <= frames && fs::exists(out / "surface" / fmt::format("{:03d}.obj", f)); ++f) {
    if (!run.stats.at("frames").at(static_cast<std::size_t>(f)).at("converged").get<bool>()) break;
    ++run.frames_written;
    const SurfaceMesh s = read_surface(out / "surface" / fmt::format("{:03d}.obj", f));
    Eigen::Matrix3Xd P(3, m.surface_vertices.cols());
    for (std::size_t v = 0; v < m.weld.size(); ++v) P.col(m.weld[v]) = s.vertices.col(static_cast<Eigen::Index>(v));
    if (surface_intersects(m.surface_triangles, P)) {
      ++run.frames_intersecting;
      if (run.first_intersecting < 0) run.first_intersecting = f;
    }
    // Each bone's capsule carried by its joint to the frame's time.
    const std::vector<Eigen::Affine3d> world = joint_world(flesh, j.at("end_time").get<double>() * f / frames);
    for (std::size_t b = 0; b < flesh.bones.size(); ++b) {
      const Bone& bone = flesh.bones[b];
      const Eigen::Affine3d motion = world[static_cast<std::size_t>(bone.joint)] * flesh.bind_world[static_cast<std::size_t>(bone.joint)].inverse();
      for (const int i : colliding[b])
        run.capsule_clearance =
            std::min(run.capsule_clearance, segment_distance(motion * bone.a, motion * bone.b, P.col(i)) - bone.radius);
    }
  }
  return run;
}

class FleshContact : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("snh-test-flesh-contact-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static inline fs::path dir_;
};

TEST_F(FleshContact, TheFistWithSelfContactAndBonesNeverIntersectsItselfOrEntersABoneAndWithoutItDoes) {
  const FistRun without = run_fist(false, dir_ / "without");
  const FistRun with = run_fist(true, dir_ / "with");
  EXPECT_TRUE(without.result.all_converged) << without.log;
  EXPECT_EQ(without.frames_written, 37);
  // With the bones' capsules the closing fist converges to frame 23. At frame 24 (t = 2, the fingers closed
  // onto the palm's capsules) Newton stalls with ‖g‖ about 50 times the tolerance: the old step rule called
  // that converged; the run now stops there and says so (docs/flesh.md, "What is not there yet").
  EXPECT_GE(with.frames_written, 24) << with.log;  // frames 0 to 23
  if (!with.result.all_converged) {
    EXPECT_NE(with.result.failure.find("no convergence"), std::string::npos) << with.result.failure;
  }
  EXPECT_GT(without.frames_intersecting, 0);  // the fingers pass into the palm and each other
  EXPECT_EQ(with.frames_intersecting, 0) << "first at frame " << with.first_intersecting;
  std::cout << "fist: without contact " << without.frames_intersecting << " of 37 frames intersect (first "
            << without.first_intersecting << "); with contact and bones " << with.frames_written << " frames converged, none intersecting"
            << (with.result.all_converged ? "" : " (stopped: " + with.result.failure + ")") << "\n";
  // The bones' capsules: no skin point they act on is inside one at any frame (without contact some are).
  EXPECT_GT(with.capsule_clearance, 0.0);
  EXPECT_LT(without.capsule_clearance, 0.0);
  std::cout << "fist: smallest distance outside a bone's capsule " << with.capsule_clearance << " with contact and bones, "
            << without.capsule_clearance << " without contact\n";

  // Statistics: with contact, pairs in range at some frames, their smallest distance within (0, d̂), CCD
  // run; without, no contact fields at all.
  const double dhat = with.stats.at("contact").at("dhat").get<double>();
  int frames_in_contact = 0;
  for (const json& f : with.stats.at("frames")) {
    const int pairs = f.at("contact_pairs").get<int>();
    if (pairs == 0) {
      EXPECT_TRUE(f.at("min_contact_distance").is_null());
      continue;
    }
    ++frames_in_contact;
    const double d = f.at("min_contact_distance").get<double>();
    EXPECT_GT(d, 0.0);
    EXPECT_LT(d, dhat);
  }
  EXPECT_GT(frames_in_contact, 0);
  EXPECT_GT(with.stats.at("ccd_calls").get<int>(), 0);
  EXPECT_GT(with.stats.at("ccd_tests").get<int>(), 0);
  EXPECT_GT(with.stats.at("contact_seconds").get<double>(), 0.0);
  for (const json& f : without.stats.at("frames")) EXPECT_FALSE(f.contains("contact_pairs"));
  EXPECT_FALSE(without.stats.contains("ccd_calls"));
  EXPECT_FALSE(without.stats.contains("contact"));
}


/// The vertices of a hex mesh whose cells do not meet through faces around them (two cells share a face when they
/// share its four vertices) while all of them lie in one face-connected part of the mesh: hinges, joints with no
/// material around them.
std::vector<int> hinge_vertices(const VolumeMesh& mesh) {
  static constexpr int kFaces[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  const auto cells = static_cast<int>(mesh.cell_count());
  std::map<std::array<int, 4>, std::vector<int>> by_face;
  for (int c = 0; c < cells; ++c)
    for (const auto& f : kFaces) {
      std::array<int, 4> key{};
      for (int k = 0; k < 4; ++k) key[static_cast<std::size_t>(k)] = mesh.cells(f[k], c);
      std::sort(key.begin(), key.end());
      by_face[key].push_back(c);
    }
  std::vector<std::vector<int>> neighbours(static_cast<std::size_t>(cells));
  UnionFind parts(static_cast<std::size_t>(cells));
  for (const auto& [key, cs] : by_face)
    if (cs.size() == 2) {
      neighbours[static_cast<std::size_t>(cs[0])].push_back(cs[1]);
      neighbours[static_cast<std::size_t>(cs[1])].push_back(cs[0]);
      parts.join(cs[0], cs[1]);
    }
  std::vector<std::vector<int>> around(static_cast<std::size_t>(mesh.vertex_count()));
  for (int c = 0; c < cells; ++c)
    for (int k = 0; k < 8; ++k) around[static_cast<std::size_t>(mesh.cells(k, c))].push_back(c);
  std::vector<int> hinges;
  for (std::size_t v = 0; v < around.size(); ++v) {
    const std::vector<int>& cs = around[v];
    if (cs.size() < 2) continue;
    std::set<int> reached{cs[0]};
    for (std::vector<int> stack{cs[0]}; !stack.empty();) {
      const int c = stack.back();
      stack.pop_back();
      for (const int d : neighbours[static_cast<std::size_t>(c)])
        if (std::find(cs.begin(), cs.end(), d) != cs.end() && reached.insert(d).second) stack.push_back(d);
    }
    const bool one_part = std::all_of(cs.begin(), cs.end(), [&](int c) { return parts.root(c) == parts.root(cs[0]); });
    if (reached.size() < cs.size() && one_part) hinges.push_back(static_cast<int>(v));
  }
  return hinges;
}

// The hand's lattice at the resolution of Figure 1's 25k-hex run (83), whose cells of one part shared a vertex at an
// edge or a corner alone in places (here 2 such hinges; the run's lattice gained 11 vertices when they were split)
// and where Newton crept on the squeezed flesh next to one: frames 10-15 took 12, 6, 6, 18, 14 and 7 iterations,
// 3-4 each once the hinges were split (docs/results.md).
TEST(FleshLattice, CellsOfOnePartShareNoVertexAtAnEdgeOrCornerAlone) {
  FleshSpec spec;
  spec.model = fs::path(SNH_SOURCE_DIR) / "data" / "hand" / "left.glb";
  spec.resolution = 83;
  spec.keyframes = {{{"wrist"}, {0.0, 1.0}, {Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()}}};
  const Flesh flesh = build_flesh(spec, "test");
  const std::vector<int> hinges = hinge_vertices(flesh.volume);
  EXPECT_TRUE(hinges.empty()) << hinges.size() << " hinge vertices, the first " << hinges.front();
}

TEST(FleshBones, CapsuleCollidersActOnTheSkinNotSkinnedAroundTheirBones) {
  FleshSpec spec;
  spec.model = fs::path(SNH_SOURCE_DIR) / "data" / "hand" / "left.glb";
  spec.resolution = 16;
  spec.keyframes = {{{"wrist"}, {0.0, 1.0}, {Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()}}};
  const auto flesh = std::make_shared<const Flesh>(build_flesh(spec, "test"));
  const RiggedModel& m = flesh->model;
  const double dhat = flesh_contact_dhat(*flesh);
  const std::vector<std::vector<int>> points = bone_collider_points(*flesh, dhat);
  const std::vector<std::shared_ptr<Term>> terms = bone_collider_terms(flesh, dhat, 1.0);
  ASSERT_EQ(points.size(), flesh->bones.size());
  const auto with_points = std::count_if(points.begin(), points.end(), [](const std::vector<int>& p) { return !p.empty(); });
  ASSERT_GT(with_points, 20);
  ASSERT_EQ(terms.size(), static_cast<std::size_t>(with_points));
  // The skin (welded points, each with its first model vertex's skin weights) at rest.
  const EmbeddedSurface skin = contact_surface(*flesh);
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(flesh->volume.vertices.data(), flesh->volume.vertices.size());
  const Eigen::Matrix3Xd rest = skin.points.apply(x);
  std::vector<int> model_vertex(static_cast<std::size_t>(rest.cols()), -1);
  for (std::size_t v = 0; v < m.weld.size(); ++v)
    if (model_vertex[static_cast<std::size_t>(m.weld[v])] < 0) model_vertex[static_cast<std::size_t>(m.weld[v])] = static_cast<int>(v);
  const auto skinned_to = [&](int i, int joint) {
    for (int k = 0; k < 4; ++k)
      if (joint >= 0 && m.joint_index(k, model_vertex[static_cast<std::size_t>(i)]) == joint &&
          m.joint_weight(k, model_vertex[static_cast<std::size_t>(i)]) > 0.0)
        return true;
    return false;
  };
  std::size_t term = 0;
  for (std::size_t b = 0; b < points.size(); ++b) {
    if (points[b].empty()) continue;
    const Bone& bone = flesh->bones[b];
    const int parent = m.skeleton.joints[static_cast<std::size_t>(bone.joint)].parent;
    EXPECT_LT(points[b].size(), static_cast<std::size_t>(rest.cols())) << bone.name;  // its own finger's skin is left out
    for (const int i : points[b]) {
      EXPECT_FALSE(skinned_to(i, bone.joint) || skinned_to(i, parent) || skinned_to(i, bone.child)) << bone.name << " point " << i;
      EXPECT_GT(segment_distance(bone.a, bone.b, rest.col(i)) - bone.radius, 2 * dhat) << bone.name << " point " << i;
    }
    // Its term acts on those points and nothing is in range at rest.
    const auto* shape = dynamic_cast<const ShapeColliderTerm*>(terms[term++].get());
    ASSERT_NE(shape, nullptr);
    EXPECT_EQ(shape->point_count(), static_cast<Eigen::Index>(points[b].size()));
    EXPECT_EQ(shape->energy(x), 0.0);
    EXPECT_GT(shape->min_distance(x), 2 * dhat);
  }
  // The middle finger's last bone acts on the ring finger's fingertip, not on its own.
  const auto bone_named = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find_if(flesh->bones.begin(), flesh->bones.end(), [&](const Bone& b) { return b.name == name; }) -
                                    flesh->bones.begin());
  };
  const std::vector<int>& middle = points.at(bone_named("middle-finger-phalanx-distal>middle-finger-tip"));
  const int ring = m.skeleton.find("ring-finger-phalanx-distal"), own = m.skeleton.find("middle-finger-phalanx-distal");
  EXPECT_TRUE(std::any_of(middle.begin(), middle.end(), [&](int i) { return skinned_to(i, ring); }));
  EXPECT_FALSE(std::any_of(middle.begin(), middle.end(), [&](int i) { return skinned_to(i, own); }));
  // The skin moved into a bone's capsule makes the energy infinite for that bone's term.
  const Bone& bone = flesh->bones[bone_named("middle-finger-phalanx-distal>middle-finger-tip")];
  Eigen::VectorXd y = x;
  for (Eigen::Index v = 0; v < flesh->volume.vertex_count(); ++v) y.segment<3>(3 * v) = 0.5 * (bone.a + bone.b);
  bool refused = false;
  for (const std::shared_ptr<Term>& t : terms) refused = refused || !std::isfinite(t->energy(y));
  EXPECT_TRUE(refused);
}

TEST(FleshColliders, ShapesActOnTheSkinAndAStartInsideOneIsRefusedNamingIt) {
  // A sphere at a skin vertex (the skin inside the lattice: the lattice's boundary would be out of the way)
  // refused at parse with the render surface named; the same sphere well away from the hand accepted.
  const fs::path file = fs::path(SNH_SOURCE_DIR) / "scenes" / "hand_fist.json";
  std::ifstream in(file);
  const json base = json::parse(in);
  const RiggedModel m = read_gltf(fs::path(SNH_SOURCE_DIR) / "data" / "hand" / "left.glb");
  const Eigen::Vector3d at = m.surface_vertices.col(100);
  const auto scene_with = [&](const Eigen::Vector3d& center) {
    json j = base;
    j["flesh"]["resolution"] = 8;
    j["contact"] = {{"self", false}};
    j["colliders"] = json::array({{{"type", "sphere"}, {"center", {center[0], center[1], center[2]}}, {"radius", 0.002}}});
    return build_scene(parse_scene(j, file));
  };
  try {
    (void)scene_with(at);
    ADD_FAILURE() << "a sphere at a skin vertex was accepted";
  } catch (const SceneError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("colliders[0]: vertex "), std::string::npos) << what;
    EXPECT_NE(what.find("of the render surface (welded) is "), std::string::npos) << what;
    EXPECT_NE(what.find("from the sphere, on or inside it at the start"), std::string::npos) << what;
  }
  EXPECT_NO_THROW((void)scene_with(at + Eigen::Vector3d(0, 0, 1)));
}

}  // namespace
}  // namespace snh
