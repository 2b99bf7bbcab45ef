// libFuzzer harness for the strict reading of a scene file's JSON (setup/scene/read_json): the input is
// the file's text; it may be rejected only with SceneError (one line). Anything else (a crash, another
// exception, a hang, runaway memory, a line break in the message) is a bug.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include <nlohmann/json.hpp>

#include "snh/setup/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    (void)snh::read_scene_json(text, "fuzz.json");
  } catch (const snh::SceneError& e) {
    if (std::string_view(e.what()).find('\n') != std::string_view::npos) std::abort();  // one line
  }
  return 0;
}
