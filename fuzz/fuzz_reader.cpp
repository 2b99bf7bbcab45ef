// libFuzzer harness for one mesh reader (SNH_FUZZ_FORMAT: msh, mesh, vtu, tetgen, obj, off, ply, stl).
// The input is written to a file with that extension and read and checked; a reader may reject it only
// with MeshError (one line). Anything else (a crash, another exception, a hang, runaway memory) is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "snh/io/mesh_read.hpp"
#include "snh/io/surface_read.hpp"

#ifndef SNH_FUZZ_FORMAT
#error "define SNH_FUZZ_FORMAT"
#endif

namespace {

const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("snh-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void put(const std::filesystem::path& p, std::string_view bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const std::string format = SNH_FUZZ_FORMAT;
  try {
    if (format == "tetgen") {  // .node, then a NUL byte, then .ele
      const std::size_t cut = bytes.find('\0');
      put(scratch() / "f.node", bytes.substr(0, cut));
      put(scratch() / "f.ele", cut == std::string_view::npos ? std::string_view() : bytes.substr(cut + 1));
      (void)snh::read_mesh(scratch() / "f.ele");
    } else if (format == "obj" || format == "off" || format == "ply" || format == "stl") {
      put(scratch() / ("f." + format), bytes);
      (void)snh::read_surface(scratch() / ("f." + format));  // tetgen itself is not fuzzed here
    } else {
      put(scratch() / ("f." + format), bytes);
      // .vtu: also every data array (how the report reads frames back).
      if (format == "vtu") (void)snh::read_vtu_data(scratch() / "f.vtu");
      (void)snh::read_mesh(scratch() / ("f." + format));
    }
  } catch (const snh::MeshError&) {
  }
  return 0;
}
