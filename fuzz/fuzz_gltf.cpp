// libFuzzer harness for the glTF reader (rig/gltf): the input is a .gltf or .glb file's bytes (the first byte
// picks the name, so JSON and binary are both tried, whatever the bytes). It may be refused only with
// RigError (one line). Anything else (a crash, another exception, a hang, runaway memory, a line break in
// the message) is a bug. The file is written to a private directory, where no external buffer exists.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "snh/rig/gltf.hpp"
#include "snh/rig/model.hpp"

namespace {

const std::filesystem::path& directory() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path d = std::filesystem::temp_directory_path() / ("snh_fuzz_gltf_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path file = directory() / ((size > 0 && data[0] == 'g') ? "model.glb" : "model.gltf");
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    (void)snh::read_gltf(file);
  } catch (const snh::RigError& e) {
    if (std::string_view(e.what()).find('\n') != std::string_view::npos) std::abort();  // one line
  }
  std::filesystem::remove(file);
  return 0;
}
