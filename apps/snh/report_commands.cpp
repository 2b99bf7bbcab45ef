#include "report_commands.hpp"

#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "../common/out_option.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/report/render.hpp"
#include "snh/report/report.hpp"
#include "snh/run/interrupt.hpp"

namespace snh::cli {
namespace {

/// Runs `work`, turning the failures that are not bad arguments into a line and an exit code: a stop
/// signal 128 + the signal, the browser failing 1 (a failure at run time, as a step that does not
/// converge), a file that cannot be written 3 (output). Bad arguments (ReportError) go on to main: 2.
template <class Work>
int exit_code_of(Work work) {
  try {
    work();
    return 0;
  } catch (const BrowserInterrupted& e) {
    std::cerr << "snh: " << e.what() << "\n";
    return 128 + e.signal;
  } catch (const BrowserError& e) {
    std::cerr << "snh: error: " << e.what() << "\n";
    return 1;
  } catch (const WriteError& e) {
    std::cerr << "snh: error: " << e.what() << "\n";
    return 3;
  }
}

}  // namespace

void add_report_commands(CLI::App& app, int& exit_code) {
  auto dir = std::make_shared<std::string>();
  CLI::App* report = app.add_subcommand(
      "report",
      "Writes (or rewrites) the browser report of an output directory of tetcli, hexcli, snh stretch, snh run, snh flesh "
      "or snh lab: DIR/index.html, which opens from the file system in any browser (3D playback of the frames, a flesh "
      "run's skin against linear blend skinning and its bones, plots of the per-step stats, the run's settings; for the "
      "lab its tables and curves). Runs write it themselves unless given --no-report.");
  report->add_option("dir", *dir, "The run's output directory")->required();
  report->callback([dir, &exit_code]() {
    exit_code = exit_code_of([&] {
      const ReportSummary s = write_report(*dir);
      std::cout << fmt::format("{} report{}: {}\n", s.kind,
                               s.kind == "lab" ? fmt::format(" (and {} simulations' reports)", s.runs)
                                               : fmt::format(" ({} frames)", s.frames),
                               std::filesystem::absolute(s.index).lexically_normal().string());
    });
  });

  struct RenderArgs {
    std::string dir, out, field, browser, show, view, fit, focus, video, frames, range, compare;
    int frame = -1, width = 1200, height = 900;
    double fps = 0.0;
    bool wireframe = false, bones = false;
  };
  auto r = std::make_shared<RenderArgs>();
  CLI::App* render = app.add_subcommand(
      "render",
      "Saves a picture of one frame of a run (the report's 3D view with its legend) as a PNG (--out), or a video of "
      "its frames (--video, with ffmpeg: Debian package ffmpeg), through headless Chromium (Debian package chromium; "
      "or set SNH_CHROMIUM). The camera frames the surface shown. Writes the report first if the directory has none.");
  render->add_option("dir", r->dir, "The run's output directory")->required();
  render->add_option("--frame", r->frame, "The frame (default: the last)")->check(finite_number(Sign::non_negative));
  render->add_option("--field", r->field, "Colour by J (default), psi (energy density) or displacement");
  CLI::Option* png = render->add_option("--out", r->out, "The PNG to write");
  CLI::Option* video = render->add_option(
      "--video", r->video,
      "A video to write instead: .mp4 (H.264) or .gif (for web pages), of every frame (or --frames) at the run's "
      "frame rate (or --fps), the camera still (--fit animation unless given)");
  png->excludes(video);
  render->add_option("--frames", r->frames, "A video's frames, FIRST:LAST (e.g. 12:36, or 12: to the end; default all)");
  render->add_option("--fps", r->fps, "A video's frames per second (default: the run's own, from its frames' times)")
      ->check(finite_number(Sign::non_negative));
  render->add_option("--width", r->width, "Picture width in pixels (default 1200)");
  render->add_option("--height", r->height, "Picture height in pixels (default 900)");
  render->add_flag("--wireframe", r->wireframe, "Draw the triangle edges");
  render->add_option("--show", r->show,
                     "A flesh run: the render surface simulated as flesh (default), posed by linear blend skinning "
                     "(lbs), the flesh coloured by its signed distance from the skinned surface in millimetres "
                     "(difference: red outside it, blue inside, with a legend), or the volume with its colours; "
                     "up to four comma-separated side by side, e.g. --show flesh,lbs");
  render->add_option("--view", r->view,
                     "The camera: three-quarter (default: front right, a little above), front, back, left, right or "
                     "top, as the model's up axis has them (glTF: +Y up, the front facing +Z)");
  render->add_option("--fit", r->fit,
                     "frame (default): the frame shown fills the picture; animation: the camera that every frame "
                     "of the run would fit (steady across frames)");
  render->add_option("--focus", r->focus,
                     "A flesh run: a close-up on a joint by name (e.g. index-finger-phalanx-proximal): the surface "
                     "round it fills the picture");
  render->add_flag("--bones", r->bones, "A flesh run: draw the bones over the surface (off by default)");
  render->add_option("--compare", r->compare,
                     "A second flesh run of the same model and frames (with and without contact, or a muscle's "
                     "activation): its skin takes the place of the skinned one (lbs, labelled with its directory) "
                     "and difference measures this run's skin from it; --show defaults to flesh,lbs");
  render->add_option("--range", r->range,
                     "--show difference: the colours' range, run (default: the whole run's distances, the same "
                     "colour for the same distance in every frame), frame (the frame's own) or LO:HI in mm");
  render->add_option("--browser", r->browser, "Chromium or Chrome binary (default: $SNH_CHROMIUM, else chromium on PATH)");
  render->callback([r, &exit_code]() {
    if (r->out.empty() == r->video.empty())
      throw CLI::ValidationError("snh render", "give --out PICTURE.png, or --video VIDEO.mp4 (or .gif)");
    RenderOptions o;
    o.frame = r->frame;
    o.field = r->field;
    o.wireframe = r->wireframe;
    o.show = r->show;
    o.view = r->view;
    o.fit = r->fit;
    o.focus = r->focus;
    o.bones = r->bones;
    o.range = r->range;
    o.compare = r->compare;
    o.width = r->width;
    o.height = r->height;
    o.out = r->out;
    o.browser = r->browser;
    o.video = r->video;
    o.frames = r->frames;
    o.fps = r->fps;
    install_stop_handlers();  // Ctrl-C stops the browser and removes what it left
    exit_code = exit_code_of([&] {
      if (r->video.empty()) {
        render_png(r->dir, o);
        std::cout << fmt::format("{} ({}x{})\n", r->out, o.width, o.height);
      } else {
        const VideoSummary v = render_video(r->dir, o);
        std::cout << fmt::format("{} ({}x{}, {} frames at {:.4g} a second)\n", r->video, o.width, o.height, v.frames, v.fps);
      }
    });
  });
}

}  // namespace snh::cli
