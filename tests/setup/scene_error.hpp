#pragma once
// The scene tests' look at a refusal: the SceneError message parse_scene gives for a scene.
#include <string>

#include <nlohmann/json.hpp>

#include "snh/setup/scene.hpp"

namespace snh::testing {

/// The SceneError message for j (read as the file "s.json"), or "" if it parses.
inline std::string error_of(const nlohmann::json& j) {
  try {
    (void)parse_scene(j, "s.json");
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

}  // namespace snh::testing
