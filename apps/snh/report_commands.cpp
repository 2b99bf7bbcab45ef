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
    std::string dir, out, field, browser, show;
    int frame = -1, width = 1200, height = 900;
    bool wireframe = false;
  };
  auto r = std::make_shared<RenderArgs>();
  CLI::App* render = app.add_subcommand(
      "render",
      "Saves a picture of one frame of a run (the report's 3D view with its legend) as a PNG, through headless "
      "Chromium (Debian package chromium; or set SNH_CHROMIUM). Writes the report first if the directory has none.");
  render->add_option("dir", r->dir, "The run's output directory")->required();
  render->add_option("--frame", r->frame, "The frame (default: the last)")->check(finite_number(Sign::non_negative));
  render->add_option("--field", r->field, "Colour by J (default), psi (energy density) or displacement");
  render->add_option("--out", r->out, "The PNG to write")->required();
  render->add_option("--width", r->width, "Picture width in pixels (default 1200)");
  render->add_option("--height", r->height, "Picture height in pixels (default 900)");
  render->add_flag("--wireframe", r->wireframe, "Draw the triangle edges");
  render->add_option("--show", r->show,
                     "A flesh run: the render surface simulated as flesh (default), posed by linear blend skinning "
                     "(lbs), or the volume with its colours")
      ->check(CLI::IsMember({"flesh", "lbs", "volume"}));
  render->add_option("--browser", r->browser, "Chromium or Chrome binary (default: $SNH_CHROMIUM, else chromium on PATH)");
  render->callback([r, &exit_code]() {
    RenderOptions o;
    o.frame = r->frame;
    o.field = r->field;
    o.wireframe = r->wireframe;
    o.show = r->show;
    o.width = r->width;
    o.height = r->height;
    o.out = r->out;
    o.browser = r->browser;
    install_stop_handlers();  // Ctrl-C stops the browser and removes what it left
    exit_code = exit_code_of([&] {
      render_png(r->dir, o);
      std::cout << fmt::format("{} ({}x{})\n", r->out, o.width, o.height);
    });
  });
}

}  // namespace snh::cli
