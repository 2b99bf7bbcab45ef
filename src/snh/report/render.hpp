#pragma once
// A picture of one frame of a run, for papers and theses: the report's 3D view (render mode: the view
// filling the window, the legend and a caption over it) saved as a PNG by headless Chromium.
#include <filesystem>
#include <string>
#include <utility>

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

/// SIGINT or SIGTERM arrived (snh::install_stop_handlers) while the browser ran: it was stopped, and
/// nothing was written.
class RenderInterrupted : public ReportError {
 public:
  explicit RenderInterrupted(int signal)
      : ReportError("interrupted by signal " + std::to_string(signal) + ": the browser was stopped, nothing was written"),
        signal(signal) {}
  int signal;
};

/// Renders a frame of the run in `dir` (writing its report first if it has none) to options.out,
/// atomically. Throws ReportError with a one-line message: a bad frame or field, no browser, the browser
/// failing or timing out, or the page reporting a problem.
void render_png(const std::filesystem::path& dir, const RenderOptions& options);

/// Width and height of a PNG file from its header; {0, 0} if it is not a PNG.
[[nodiscard]] std::pair<int, int> png_size(const std::filesystem::path& png);

}  // namespace snh
