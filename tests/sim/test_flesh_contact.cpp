// Flesh with contact on its render surface (the WebXR hand closing into a fist, scenes/hand_fist.json, the
// whole clip: the fingers close, then the wrist turns with the fist closed): with self-contact no two triangles
// of the welded render surface intersect at any frame (the brute-force test of tests/contact/surface_checks.hpp
// over the whole surface); without it they do. The contact statistics: pairs in range and a smallest
// distance within (0, d̂) with contact, no contact fields without.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "contact/surface_checks.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/fem/collider_term.hpp"
#include "snh/sim/flesh.hpp"
#include "snh/sim/scene.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct FistRun {
  Scene scene;
  SceneResult result;
  std::string log;
  json stats;
  int frames_intersecting = 0;
  int first_intersecting = -1;
};

/// The fist (36 frames to t = 3) at the scene's lattice resolution 24, with or without self-contact.
FistRun run_fist(bool self_contact, const fs::path& out) {
  const fs::path file = fs::path(SNH_SOURCE_DIR) / "scenes" / "hand_fist.json";
  std::ifstream in(file);
  json j = json::parse(in);
  j["output"] = {{"dir", out.string()}};
  if (self_contact) j["contact"] = {{"self", true}};
  FistRun run;
  run.scene = parse_scene(j, file);
  std::ostringstream log;
  run.result = run_scene(run.scene, log);
  run.log = log.str();
  std::ifstream st(out / "stats.json");
  run.stats = json::parse(st);
  // Every frame's render surface (model order), welded, checked for intersecting triangles.
  const Flesh& flesh = *run.scene.loaded->flesh;
  const RiggedModel& m = flesh.model;
  for (int f = 0; f <= j.at("frames").get<int>(); ++f) {
    const SurfaceMesh s = read_surface(out / "surface" / fmt::format("{:03d}.obj", f));
    Eigen::Matrix3Xd P(3, m.surface_vertices.cols());
    for (std::size_t v = 0; v < m.weld.size(); ++v) P.col(m.weld[v]) = s.vertices.col(static_cast<Eigen::Index>(v));
    if (surface_intersects(m.surface_triangles, P)) {
      ++run.frames_intersecting;
      if (run.first_intersecting < 0) run.first_intersecting = f;
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

TEST_F(FleshContact, TheFistWithSelfContactNeverIntersectsItselfAndWithoutItDoes) {
  const FistRun without = run_fist(false, dir_ / "without");
  const FistRun with = run_fist(true, dir_ / "with");
  EXPECT_TRUE(without.result.all_converged) << without.log;
  EXPECT_TRUE(with.result.all_converged) << with.log;
  EXPECT_GT(without.frames_intersecting, 0);  // the fingers pass into the palm and each other
  EXPECT_EQ(with.frames_intersecting, 0) << "first at frame " << with.first_intersecting;
  std::cout << "fist: without contact " << without.frames_intersecting << " of 37 frames intersect (first "
            << without.first_intersecting << ")\n";

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


TEST(FleshBones, CapsuleCollidersHoldTheFreeBoundaryVerticesFarFromTheirBonesOnly) {
  FleshSpec spec;
  spec.model = fs::path(SNH_SOURCE_DIR) / "data" / "hand" / "left.glb";
  spec.resolution = 16;
  spec.keyframes = {{{"wrist"}, {0.0, 1.0}, {Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()}}};
  const auto flesh = std::make_shared<const Flesh>(build_flesh(spec, "test"));
  const double dhat = 1e-4;
  const std::vector<std::shared_ptr<Term>> terms = bone_collider_terms(flesh, dhat, 1.0);
  ASSERT_FALSE(terms.empty());
  EXPECT_LE(terms.size(), flesh->bones.size());
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(flesh->volume.vertices.data(), flesh->volume.vertices.size());
  for (const std::shared_ptr<Term>& t : terms) {
    const auto* shape = dynamic_cast<const ShapeColliderTerm*>(t.get());
    ASSERT_NE(shape, nullptr);
    // At rest nothing is in range (the first layer around a capsule and the bound vertices are left out).
    EXPECT_EQ(t->energy(x), 0.0);
    EXPECT_GT(shape->min_distance(x), std::max(flesh->cell_size, 2 * dhat));
  }
  // A vertex moved into a bone's capsule makes the energy infinite for that bone's term.
  const Bone& bone = *std::find_if(flesh->bones.begin(), flesh->bones.end(), [](const Bone& b) { return b.radius > 0.0; });
  bool refused = false;
  for (const std::shared_ptr<Term>& t : terms) {
    Eigen::VectorXd y = x;
    for (Eigen::Index v = 0; v < flesh->volume.vertex_count(); ++v) y.segment<3>(3 * v) = 0.5 * (bone.a + bone.b);
    refused = refused || !std::isfinite(t->energy(y));
  }
  EXPECT_TRUE(refused);
}

}  // namespace
}  // namespace snh
