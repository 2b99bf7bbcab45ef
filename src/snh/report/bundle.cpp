// The viewer script, embedded in the library at build time: src/CMakeLists.txt bundles viewer/ with
// esbuild into SNH_BUNDLE_PATH, and the assembler's .incbin places that file's bytes here.
#include "snh/report/report.hpp"

#ifndef SNH_BUNDLE_PATH
#error "SNH_BUNDLE_PATH (the bundled viewer script) must be defined by the build"
#endif

asm(".pushsection .rodata\n"
    ".balign 16\n"
    "snh_report_bundle_begin:\n"
    ".incbin \"" SNH_BUNDLE_PATH "\"\n"
    "snh_report_bundle_end:\n"
    ".popsection\n");

extern "C" const char snh_report_bundle_begin[];
extern "C" const char snh_report_bundle_end[];

namespace snh {

std::string_view report_bundle() {
  return {snh_report_bundle_begin, static_cast<std::size_t>(snh_report_bundle_end - snh_report_bundle_begin)};
}

}  // namespace snh
