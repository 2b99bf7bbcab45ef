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
  /// A flesh run: "flesh", "lbs", "difference" (the flesh coloured by its signed distance from the skinned
  /// surface) or "volume", or up to four of them comma-separated, side by side ("": flesh)
  std::string show;
  std::string view;          ///< the camera: three-quarter (""), front, back, left, right or top
  /// "frame" (""): the frame's own shape fills the picture; "animation": the camera that every frame fits
  std::string fit;
  std::string focus;         ///< a flesh run: a joint's name, for a close-up on the surface round it
  bool bones = false;        ///< a flesh run: draw the bones over the surface
  /// --show difference: the colours' range, "run" (""), "frame" or "LO:HI" in millimetres
  std::string range;
  int width = 1200, height = 900;  ///< picture size in pixels
  std::filesystem::path out;       ///< the PNG to write
  std::string browser;       ///< Chromium's path ("": $SNH_CHROMIUM, else chromium or google-chrome on PATH)
  double timeout_seconds = 120.0;  ///< per browser run (a video: and 10 s a frame)
  /// A second flesh run of the same skin and frames: shown as "lbs" (its skin) and measured against by
  /// "difference" (the distance of this run's skin from its skin), labelled by the runs' directories.
  std::filesystem::path compare;
  std::filesystem::path video;     ///< render_video: the .mp4 or .gif to write
  std::string frames;        ///< render_video: "FIRST:LAST" (either may be left out; "": every frame)
  double fps = 0.0;          ///< render_video: frames a second (0: the run's own rate, from the frames' times)
};

/// ffmpeg, which makes a video of the frames, is missing or failed: a failure at run time, as the browser's.
class EncoderError : public BrowserError {
 public:
  using BrowserError::BrowserError;
};

struct VideoSummary {
  int frames = 0;
  double fps = 0.0;
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

/// Renders the frames FIRST to LAST of the run in `dir` as a video (options.video: .mp4, H.264, or .gif), one
/// browser drawing them in turn with the same camera (by default the one every frame fits: --fit animation)
/// and ffmpeg (Debian package ffmpeg) making the video at the run's frame rate, written atomically. Throws
/// as render_png, and EncoderError when ffmpeg is missing or fails. Returns the frames and the rate.
VideoSummary render_video(const std::filesystem::path& dir, const RenderOptions& options);

/// --compare: a run directory in `into` that holds the run in `dir` (its files linked) with the skin of the
/// run in `other` as its "lbs" surface, and its report written with the runs' names as the surfaces' labels:
/// the difference is the distance of dir's skin from other's. Throws ReportError (one line) unless both
/// are flesh runs of one skin (vertex count and triangles) with as many frames.
std::filesystem::path comparison_run(const std::filesystem::path& dir, const std::filesystem::path& other,
                                     const std::filesystem::path& into);

/// Width and height of a PNG file from its header; {0, 0} if it is not a PNG.
[[nodiscard]] std::pair<int, int> png_size(const std::filesystem::path& png);

}  // namespace snh
