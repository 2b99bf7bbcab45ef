// Scene files that must be refused (issue 13): each bad input is one SceneError line naming the file and the
// key or value at fault, before any work is done.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "snh/sim/scene.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

/// The SceneError message for j, or "" if it parses.
std::string error_of(const json& j) {
  try {
    (void)parse_scene(j, "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

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
  for (std::size_t at; (at = out.find(path.string())) != std::string::npos;) out.replace(at, path.string().size(), "F");
  return out;
}

bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

TEST(SceneInput, LameParametersGoTogether) {
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1000}})")), "s.json: material: mu and lambda go together (got mu, no lambda)");
  EXPECT_EQ(error_of(json::parse(R"({"material": {"lambda": 1000}})")),
            "s.json: material: mu and lambda go together (got lambda, no mu)");
  EXPECT_EQ(error_of(json::parse(R"({"material": {"mu": 1000, "lambda": 2000}})")), "");
}

}  // namespace
}  // namespace snh
