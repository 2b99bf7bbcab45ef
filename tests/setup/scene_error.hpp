#pragma once
// The scene tests' look at a refusal: the SceneError message the parse or the build gives for a scene.
#include <string>

#include <nlohmann/json.hpp>

#include "snh/setup/scene_build.hpp"

namespace snh::testing {

/// The SceneError message for j (read as the file "s.json"), or "" if it parses and builds.
inline std::string error_of(const nlohmann::json& j) {
  try {
    (void)build_scene(parse_scene(j, "s.json"));
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace snh::testing
