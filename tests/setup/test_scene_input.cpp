// Scene files that must be refused (issue 13): each bad input is one SceneError line naming the file and the
// key or value at fault, before any work is done.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "io/bytes_read.hpp"
#include "scene_error.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

using testing::error_of;

/// The SceneError message for the scene file holding `text`, or "" if it loads; the file's name is replaced by "F".
std::string file_error_of(const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("snh_scene_input_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << text;
  std::string out;
  try {
    (void)load_scene(path);
  } catch (const SceneError& e) {
    out = e.what();
  }
  std::filesystem::remove(path);
  for (std::size_t at; (at = out.find(path.string())) != std::string::npos;)
    out = out.substr(0, at) + "F" + out.substr(at + path.string().size());
  return out;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(SceneInput, LameParametersGoTogether) {
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1000}})")), "s.json: material: mu and lambda go together (got mu, no lambda)");
  EXPECT_EQ(error_of(json::parse(R"({"material": {"lambda": 1000}})")),
            "s.json: material: mu and lambda go together (got lambda, no mu)");
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1000, "lambda": 2000}})")), "");
}

TEST(SceneInput, RunsThatCannotBeDoneAreRefused) {
  // The substep count was an int that overflowed (one substep per frame instead); now counted in double.
  EXPECT_EQ(error_of(json::parse(R"({"dt": 1e-11})")),
            "s.json: dt: 1e-11 with end_time 1 over 25 frames makes 1e+11 substeps; at most 1e+08 can run (raise dt or lower end_time)");
  EXPECT_TRUE(contains(error_of(json::parse(R"({"dt": 1e-300})")), "s.json: dt: 1e-300 with end_time 1 over 25 frames makes 1e+300 substeps"));
  EXPECT_TRUE(contains(error_of(json::parse(R"({"end_time": 1e15})")), "s.json: dt: 0.01 with end_time 1e+15 over 25 frames makes 1e+17"));
  EXPECT_EQ(error_of(json::parse(R"({"end_time": 1e308})")), "s.json: end_time: must be at most 1e+15 in magnitude, got 1e+308");
  EXPECT_TRUE(contains(error_of(json::parse(R"({"dt": 1e-7, "end_time": 10.1})")), "makes 1.01e+08 substeps"));
  EXPECT_EQ(error_of(json::parse(R"({"dt": 1e-7, "end_time": 10})")), "") << "1e8 substeps in all may run";
  EXPECT_EQ(error_of(json::parse(R"({"frames": 100001})")), "s.json: frames: must be from 1 to 100000, got 100001");
  EXPECT_EQ(error_of(json::parse(R"({"integrator": "quasi_static", "dt": 1e-300})")), "") << "dt unused when quasi-static";
  // A scene built in code is checked when it runs.
  Scene s;
  s.source = "code";
  s.time.dt = 1e-12;
  s.output.dir = std::filesystem::temp_directory_path() / ("snh_scene_input_run_" + std::to_string(::getpid()));
  std::ostringstream log;
  try {
    (void)run_scene(s, log);
    ADD_FAILURE() << "no error";
  } catch (const SceneError& e) {
    EXPECT_TRUE(contains(e.what(), "code: dt: 1e-12 with end_time 1 over 25 frames makes 1e+12 substeps")) << e.what();
  }
  std::filesystem::remove_all(s.output.dir);
}

TEST(SceneInput, KeysGivenTwiceAreRefused) {
  // nlohmann keeps the last of two equal keys silently; a scene names the key instead.
  EXPECT_EQ(file_error_of(R"({"dt": 0.01, "dt": 0.02})"), "F: dt: the key is given twice in the same object (give each key once)");
  EXPECT_EQ(file_error_of(R"({"pins": [{"indices": [0]}, {"indices": [1], "axes": "x", "axes": "y"}]})"),
            "F: pins[1].axes: the key is given twice in the same object (give each key once)");
  EXPECT_EQ(file_error_of(R"({"mesh": {"box": {"res": 2, "min": [0, 0, 0], "res": 3}}})"),
            "F: mesh.box.res: the key is given twice in the same object (give each key once)");
  EXPECT_EQ(file_error_of(R"({"initial": [[], {"type": "perturb"}, {"type": "perturb", "seed": 1, "seed": 2}]})"),
            "F: initial[2].seed: the key is given twice in the same object (give each key once)");
  // The same key in different objects is fine.
  EXPECT_EQ(file_error_of(R"({"mesh": {"box": {"min": [0, 0, 0], "max": [1, 1, 1]}},
                              "pins": [{"region": {"min": [0, 0, 0], "max": [1, 1, 0]}}], "frames": 1})"), "");
}

// JSON text holds no NUL byte: a scene followed by NUL padding was taken as the scene alone (nlohmann's lexer
// ends the input at a NUL) after the whole file was read; it is refused, having read about as much as the text.
TEST(SceneInput, ANulByteIsRefusedWhereItIs) {
  EXPECT_EQ(file_error_of(std::string("{\n  \"dt\": 0.01\n}\n\0\0\0", 18)), "F: line 4: binary data (a NUL byte) where JSON text was expected");
  EXPECT_EQ(file_error_of(std::string("{\"dt\": 0.") + '\0' + "1}"), "F: line 1: binary data (a NUL byte) where JSON text was expected");
  if (test::bytes_read() < 0) GTEST_SKIP() << "no /proc/self/io";
  const auto path = std::filesystem::temp_directory_path() / ("snh_scene_padded_" + std::to_string(::getpid()) + ".json");
  std::ofstream(path) << R"({"mesh": {"box": {"res": 2}}, "frames": 1})" << "\n";
  std::filesystem::resize_file(path, 300u << 20);
  const long long before = test::bytes_read();
  std::string error;
  try {
    (void)load_scene(path);
  } catch (const SceneError& e) {
    error = e.what();
  }
  const long long read = test::bytes_read() - before;
  std::filesystem::remove(path);
  EXPECT_EQ(error, path.string() + ": line 2: binary data (a NUL byte) where JSON text was expected");
  EXPECT_LT(read, 8 << 20) << "read " << read << " bytes";
}

TEST(SceneInput, NumbersOutOfRangeAndDeepNestingAreOneLine) {
  EXPECT_EQ(file_error_of("{\n  \"dt\": 0.01,\n  \"end_time\": 1e309\n}"), "F: line 3: number out of range: 1e309");
  EXPECT_EQ(file_error_of("{\"gravity\": [0, -1e400, 0]}"), "F: line 1: number out of range: -1e400");
  EXPECT_EQ(file_error_of("{\"dt\": 1" + std::string(400, '0') + "}"),
            "F: line 1: number out of range: 1" + std::string(39, '0') + "...");
  EXPECT_EQ(file_error_of(R"({"gravity": [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]]})"),
            "F: gravity[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]"
            "[0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0][0]: nested deeper than 64 levels");
  const std::string bad = file_error_of("{\"dt\": 0.1,");
  EXPECT_TRUE(contains(bad, "F: not valid JSON: ")) << bad;
  EXPECT_TRUE(contains(bad, "line 1")) << bad;
  EXPECT_EQ(file_error_of(""), file_error_of("")) << "empty file";
  EXPECT_TRUE(contains(file_error_of(""), "F: not valid JSON")) << file_error_of("");
}

TEST(SceneInput, ValuesOutsideTheDocumentedRangeAreRefused) {
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"min": [-1e308, 0, 0]}}})")),
            "s.json: mesh.box.min: expected 3 numbers at most 1e+15 in magnitude, got [-1e+308,0,0]");
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"min": [0, 0, 0], "max": [1e200, 1, 1]}}})")),
            "s.json: mesh.box.max: expected 3 numbers at most 1e+15 in magnitude, got [1e+200,1,1]");
  EXPECT_EQ(error_of(json::parse(R"({"gravity": [0, -1e16, 0]})")),
            "s.json: gravity: expected 3 numbers at most 1e+15 in magnitude, got [0,-1e+16,0]");
  EXPECT_EQ(error_of(json::parse(R"({"density": 1e200})")), "s.json: density: must be at most 1e+15 in magnitude, got 1e+200");
  EXPECT_EQ(error_of(json::parse(R"({"damping": {"mass": 2e15}})")), "s.json: damping.mass: must be at most 1e+15 in magnitude, got 2e+15");
  EXPECT_EQ(error_of(json::parse(R"({"initial": [{"type": "scale", "factors": [1e16, 1, 1]}]})")),
            "s.json: initial[0].factors: expected 3 numbers at most 1e+15 in magnitude, got [1e+16,1,1]");
  EXPECT_EQ(error_of(json::parse(R"({"pins": [{"indices": [0], "motion": [{"type": "translate", "by": [1e300, 0, 0]}]}]})")),
            "s.json: pins[0].motion[0].by: expected 3 numbers at most 1e+15 in magnitude, got [1e+300,0,0]");
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1e300, "lambda": 1}})")),
            "s.json: material.mu: must be at most 1e+15 in magnitude, got 1e+300");
  // In range one by one, out of range together: the initial operations' product is checked too.
  EXPECT_EQ(error_of(json::parse(R"({"initial": [{"type": "scale", "factors": [1e15, 1, 1]}, {"type": "scale", "factors": [1e15, 1, 1]}]})")),
            "s.json: initial: the operations move a vertex beyond the 1e+15 a scene allows (largest coordinate 1e+30)");
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"min": [-1e15, -1e15, -1e15], "max": [1e15, 1e15, 1e15]}}, "frames": 1})")), "");
}

TEST(SceneInput, PinSetsDrivingOneVertexDifferentlyAreRefused) {
  // Vertex 1 held in x by a still set, and moved in x and y by a set holding y: contradictory targets, silently
  // combined before.
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"res": 2}}, "pins": [{"indices": [0, 1], "axes": "x"},
              {"indices": [1, 2], "axes": "y", "motion": [{"type": "translate", "by": [0.1, 0.1, 0]}]}]})")),
            "s.json: pins[0] and pins[1] both drive vertex 1 in different ways: pins[1] moves it along x (to 0.1 at t = 1), "
            "which pins[0] holds at 0; give each vertex to one pin set");
  EXPECT_TRUE(contains(error_of(json::parse(R"({"mesh": {"box": {"res": 2}}, "pins": [{"indices": [5], "axes": "z",
              "motion": [{"type": "rotate", "center": [0, 0, 0], "axis": [0, 0, 1], "degrees": 10}]}, {"indices": [3, 4, 5], "axes": "xy"}]})")),
                       "s.json: pins[0] and pins[1] both drive vertex 5 in different ways: pins[0] moves it along x"));
  // The same coordinate twice was already refused; sets sharing a vertex on different axes agree when the moving
  // one moves it only along its own axes (the symmetry planes of scenes/poisson_bar.json).
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"res": 2}}, "pins": [{"indices": [0, 1]}, {"indices": [1]}]})")),
            "s.json: pins[1] holds the x coordinate of vertex 1, which pins[0] already holds: give each coordinate one motion");
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"res": 2}}, "pins": [{"indices": [0, 1], "axes": "x"}, {"indices": [1], "axes": "yz"}]})")), "");
  EXPECT_EQ(error_of(json::parse(R"({"mesh": {"box": {"res": 2}}, "pins": [{"indices": [0, 1], "axes": "x"},
              {"indices": [1, 2], "axes": "y", "motion": [{"type": "translate", "by": [0, 0.1, 0]}]}]})")), "");
}

TEST(SceneRunGuard, ANonFiniteStateStopsTheRunAndKeepsTheCompletedFrames) {
  // A scene made in code (unchecked) whose pin's target is NaN: no NaN may reach a frame or the log (before, frame 1
  // was written and its line printed "|g| = inf, energy nan" and blamed J <= 0).
  Scene s;
  s.source = "code";
  s.mesh.resolution = 2;
  s.time.frames = 4;
  s.time.end_time = 1.0;
  s.time.dt = 0.25;
  s.pins.push_back({.select = {.region = std::nullopt, .indices = {0}}, .axes = {true, true, true},
                    .motions = {Translate{.by = Eigen::Vector3d(std::nan(""), 0, 0), .start = 0.5, .end = 1.0}}});
  s.output.dir = std::filesystem::temp_directory_path() / ("snh_scene_guard_" + std::to_string(::getpid()));
  std::ostringstream log;
  const SceneResult r = run_scene(s, log);
  EXPECT_FALSE(r.all_converged);
  EXPECT_EQ(r.failure, "frame 1: the state is not finite (NaN or Inf) after t = 0.25; stopped, frames 000 to 000 kept") << r.failure;
  EXPECT_EQ(r.frames.size(), 1u) << "the initial state";
  EXPECT_TRUE(r.final_positions.allFinite()) << "the last completed frame's state";
  EXPECT_FALSE(contains(log.str(), "nan")) << log.str();
  EXPECT_FALSE(contains(log.str(), "inf")) << log.str();
  EXPECT_TRUE(std::filesystem::exists(s.output.dir / "000.obj"));
  EXPECT_FALSE(std::filesystem::exists(s.output.dir / "001.obj"));
  std::ifstream stats(s.output.dir / "stats.json");
  const json j = json::parse(stats);
  EXPECT_EQ(j["status"], "stopped");
  EXPECT_EQ(j["frames"].size(), 1u);
  EXPECT_EQ(j["failure"], r.failure);
  std::filesystem::remove_all(s.output.dir);
}

}  // namespace
}  // namespace snh
