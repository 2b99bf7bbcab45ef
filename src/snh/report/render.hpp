#pragma once
// A picture of one frame of a run, for papers and theses: the report's 3D view (render mode: the view
// filling the window, the legend and a caption over it) saved as a PNG by headless Chromium.
#include <filesystem>
#include <string>
#include <utility>

#include "snh/report/browser.hpp"  // BrowserError, BrowserInterrupted
#include "snh/report/report.hpp"

namespace snh {

struct RenderOptions {
  int frame = -1;            ///< the frame (−1: the last)
  std::string field;         ///< the field colouring the surface ("": the report's default, J)
  bool wireframe = false;    ///< draw the triangle edges
  std::string show;          ///< a flesh run: "flesh", "lbs" or "volume" ("": the report's default, flesh)
  int width = 1200, height = 900;  ///< picture size in pixels
  std::filesystem::path out;       ///< the PNG to write
  std::string browser;       ///< Chromium's path ("": $SNH_CHROMIUM, else chromium or google-chrome on PATH)
  double timeout_seconds = 120.0;  ///< per browser run
};

/// Renders a frame of the run in `dir` (writing its report first if it has none) to options.out,
/// atomically, by a headless browser that takes the picture once the page says it drew the frame.
/// Throws, each with a one-line message:
///   ReportError         a bad argument or run: picture size, --out a directory, a device or in a missing
///                       directory, frame, field, --show, a browser given that cannot be run;
///   BrowserError        the browser failed: none found, it did not start, ended, crashed or timed out,
///                       or the page reported a problem;
///   BrowserInterrupted  SIGINT or SIGTERM arrived (snh::install_stop_handlers): the browser was killed;
///   WriteError          the picture could not be written.
/// The browser's temporary profile is removed however it ends.
void render_png(const std::filesystem::path& dir, const RenderOptions& options);

/// Width and height of a PNG file from its header; {0, 0} if it is not a PNG.
[[nodiscard]] std::pair<int, int> png_size(const std::filesystem::path& png);

}  // namespace snh
