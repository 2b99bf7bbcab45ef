// Impacts: a rubber cube thrown at the ground at 20, 50 and 100 m/s (a step of 4 ms carries it up to twice
// its own size) lands, never passes through, never inverts, and bounces, by backward Euler and by BDF2 (and
// at 20 and 50 m/s by TR-BDF2, which at 100 m/s converges and crushes it as short steps do), BDF2 and TR-BDF2
// keeping more of its speed; a flesh cube at 100 m/s (five times its compression wave speed) lands with
// every whole step converged, and where Newton is allowed fewer iterations, steps retried in halves get it
// through, and only they.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/setup/scene.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

/// A 0.2 m cube of 4³ hexes, its bottom 5 cm above a ground plane, thrown down at `speed`.
json thrown_cube(double youngs, double speed, const char* integrator) {
  json j = json::parse(R"({
    "mesh": {"box": {"element": "hex", "res": 4, "min": [-0.1, 0.05, -0.1], "max": [0.1, 0.25, 0.1]}},
    "material": {"name": "stable_neo_hookean", "poisson": 0.45},
    "density": 1100, "dt": 0.004, "end_time": 0.2, "frames": 50, "gravity": [0, -9.81, 0],
    "contact": {"dhat": 0.002},
    "colliders": [{"type": "plane", "point": [0, 0, 0], "normal": [0, 1, 0]}],
    "output": {"vtu": false}})");
  j["material"]["youngs"] = youngs;
  j["integrator"] = integrator;
  j["initial"] = json::array({{{"type", "velocity"}, {"value", {0.0, -speed, 0.0}}}});
  return j;
}

/// Every vertex's height (y) in a frame's OBJ.
std::vector<double> heights(const fs::path& obj) {
  std::ifstream in(obj);
  std::vector<double> y;
  for (std::string line; std::getline(in, line);)
    if (line.rfind("v ", 0) == 0) {
      std::istringstream s(line.substr(2));
      double a = 0, b = 0, c = 0;
      s >> a >> b >> c;
      y.push_back(b);
    }
  return y;
}

struct Landing {
  SceneResult result;
  double lowest = 1e9;       ///< the lowest vertex of any frame
  double final_centre = 0.0; ///< the mean height at the end
};

Landing land(const json& j, const std::string& name) {
  Scene s = parse_scene(j, name + ".json");
  s.output.dir = fs::temp_directory_path() / fmt::format("snh_test_impact_{}_{}", name, ::getpid());
  fs::remove_all(s.output.dir);
  std::ostringstream log;
  Landing l{.result = run_scene(s, log)};
  for (std::size_t f = 0; f < l.result.frames.size(); ++f) {
    const std::vector<double> y = heights(s.output.dir / fmt::format("{:03d}.obj", f));
    if (y.empty()) continue;  // a frame not written (a failed run)
    for (double v : y) l.lowest = std::min(l.lowest, v);
    double sum = 0.0;
    for (double v : y) sum += v;
    l.final_centre = sum / static_cast<double>(y.size());
  }
  fs::remove_all(s.output.dir);
  return l;
}

/// Every frame with contact pairs keeps them apart (its smallest distance positive).
void expect_pairs_apart(const SceneResult& result) {
  for (const StepRecord& f : result.frames) {
    if (f.contact_pairs > 0) {
      EXPECT_GT(f.min_contact_distance, 0.0) << "frame " << f.index;
    }
  }
}

TEST(Impact, ARubberCubeThrownAtTheGroundBouncesWithoutPassingThrough) {
  for (const double speed : {20.0, 50.0, 100.0}) {
    // At 100 m/s (1.7 times the rubber's compression wave speed) the model crushes the cube: every integrator
    // does at steps of 2 ms and below (docs/results.md). At 4 ms backward Euler and BDF2 land it clean, their
    // damping taking up the impact; TR-BDF2, which damps little, crushes it as the short steps do. It still
    // converges at every frame and keeps its contact pairs apart.
    double rebound[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < 3; ++i) {
      const char* integrator = i == 0 ? "backward_euler" : i == 1 ? "bdf2" : "tr_bdf2";
      SCOPED_TRACE(fmt::format("{} m/s, {}", speed, integrator));
      const Landing l = land(thrown_cube(1e6, speed, integrator), fmt::format("rubber_{}_{}", speed, integrator));
      ASSERT_TRUE(l.result.all_converged) << l.result.failure;
      ASSERT_EQ(l.result.frames.size(), 51u);
      expect_pairs_apart(l.result);
      rebound[i] = l.final_centre;
      EXPECT_GT(l.final_centre, 0.3) << "it bounced back up past where it started";
      if (i == 2 && speed == 100.0) continue;
      EXPECT_GT(l.lowest, 0.0) << "no vertex reaches the ground";
      for (const StepRecord& f : l.result.frames) {
        EXPECT_EQ(f.inverted, 0) << "frame " << f.index;
        EXPECT_EQ(f.substeps, f.index == 0 ? 0 : 1) << "frame " << f.index << ": no step needed halving";
      }
    }
    std::cout << speed << " m/s: the centre ends at " << rebound[0] << ", " << rebound[1] << " and " << rebound[2]
              << " (backward Euler, BDF2, TR-BDF2)\n";
    EXPECT_GT(rebound[1], 2.0 * rebound[0]) << "BDF2 keeps more of the rebound's speed";
    if (speed < 100.0) {
      EXPECT_GT(rebound[2], 2.0 * rebound[0]) << "TR-BDF2 keeps more of the rebound's speed";
    }
  }
}

TEST(Impact, AFleshCubeAtAHundredMetresASecondLandsAndAStepThatFailsIsRetriedInHalves) {
  // E = 100 kPa: compression waves travel at about 20 m/s, and at 100 m/s the cube is crushed inside out
  // (its surface stays above the ground; inverted cells are warned of). Every whole BDF2 step converges
  // within the 50 Newton iterations allowed (the one after the impact takes 40: it failed before the line
  // search doubled the full steps that the compressed and inverted cells' clamped curvature cut short).
  json j = thrown_cube(1e5, 100.0, "bdf2");
  const Landing whole = land(j, "flesh_whole");
  EXPECT_TRUE(whole.result.all_converged) << whole.result.failure;
  for (const StepRecord& f : whole.result.frames)
    EXPECT_EQ(f.substeps, f.index == 0 ? 0 : 1) << "frame " << f.index << ": no step needed halving";
  expect_pairs_apart(whole.result);
  // With 30 Newton iterations allowed a whole step after the impact fails, and its halves get through.
  j["solver"] = {{"max_iterations", 30}};
  const Landing retried = land(j, "flesh_retried");
  EXPECT_TRUE(retried.result.all_converged) << retried.result.failure;
  int extra = 0;
  for (const StepRecord& f : retried.result.frames)
    if (f.index > 0) extra += f.substeps - 1;
  expect_pairs_apart(retried.result);
  EXPECT_GT(extra, 0) << "some step was retried in halves";
  j["solver"]["step_halvings"] = 0;
  const Landing stopped = land(j, "flesh_stopped");
  EXPECT_FALSE(stopped.result.all_converged) << "without halving, a step fails";
}

}  // namespace
}  // namespace snh
