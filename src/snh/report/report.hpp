#pragma once
// The browser report of a run (docs/design.md): DIR/index.html with the run's data beside it, a page
// that opens from the file system (file://, no server) and shows the frames in 3D (three.js), the
// per-step stats as plots (uPlot), the run's settings, and for the lab its tables and curves.
//
// What is written (every file atomically, index.html last):
//   DIR/index.html               the page: loads report/data.js, then the bundled viewer script
//   DIR/report/snh-report.js     the viewer (viewer/, built by esbuild and embedded in the library)
//   DIR/report/data.js           window.SNH_REPORT = {...}: settings, status, tables, plots, surface topology
//   DIR/report/frames/NNN.js     one per frame: surface positions and fields (base64 Float32), loaded lazily
// The report is made from what the run left on disk (stats.json, frames.pvd and the .vtu frames, or
// lab.json), so `snh report DIR` remakes it for any output directory.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "snh/io/base64.hpp"  // base64_encode, declared here before it moved to io/

namespace snh {

/// A directory the report cannot be made for; the message is one line naming the file at fault.
class ReportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ReportOptions {
  /// The viewer script as the page loads it, relative to DIR (lab sub-runs share the lab's copy).
  std::string bundle_src = "report/snh-report.js";
  bool write_bundle = true;  ///< write DIR/report/snh-report.js
};

struct ReportSummary {
  std::filesystem::path index;  ///< DIR/index.html
  std::string kind;             ///< "stretch", "scene" or "lab"
  int frames = 0;               ///< frames in the 3D view (0: none)
  int runs = 0;                 ///< lab: the sub-runs' reports written
};

/// Writes the report of the run or lab in `dir` (a lab when dir/lab.json exists, else dir/stats.json).
/// A lab's report also writes one for every simulation under it. Throws ReportError for a directory the
/// report cannot be made for (missing, not a directory, not a run, damaged files), WriteError when a
/// file of the report cannot be written.
ReportSummary write_report(const std::filesystem::path& dir, const ReportOptions& options = {});

/// The data of the report in `dir` (DIR/report/data.js) read back. Throws ReportError.
[[nodiscard]] nlohmann::json read_report_data(const std::filesystem::path& dir);

/// The viewer script embedded at build time (viewer/ bundled by esbuild).
[[nodiscard]] std::string_view report_bundle();

}  // namespace snh
