// libFuzzer harness for reading checkpoint.bin (run/checkpoint, what `--resume` reads). Each input is read
// twice: as it is (almost always refused by its checksum) and with its correct FNV-1a digest appended, so
// that the fields behind the checksum (the fingerprint, step, time and vector lengths) are fuzzed too; the
// resume check then compares it with a run. A damaged file may be refused only with std::runtime_error
// (reading) or std::invalid_argument (resuming), each one line. Anything else (a crash, another exception,
// a hang, runaway memory, a line break in a message) is a bug.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "snh/io/checksum.hpp"
#include "snh/run/checkpoint.hpp"

namespace {

const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("snh-fuzz-checkpoint-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

void one_line(const std::exception& e) {
  if (std::string_view(e.what()).find('\n') != std::string_view::npos) std::abort();
}

void read(std::string_view bytes) {
  std::ofstream(scratch() / "checkpoint.bin", std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  try {
    (void)snh::read_checkpoint(scratch());
  } catch (const std::runtime_error& e) {
    one_line(e);
  }
  try {
    (void)snh::checkpoint_for_resume(scratch(), "stretch: tet4 res 2", 81);
  } catch (const std::invalid_argument& e) {
    one_line(e);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  read(bytes);
  const std::uint64_t digest = snh::fnv1a64(bytes);
  read(bytes + std::string(reinterpret_cast<const char*>(&digest), sizeof(digest)));
  return 0;
}
