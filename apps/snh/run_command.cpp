#include "run_command.hpp"

#include <filesystem>
#include <iostream>
#include <memory>

#include <omp.h>
#include <unistd.h>

#include "../common/command_line.hpp"
#include "../common/out_option.hpp"
#include "../common/run_report.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/setup/scene_run.hpp"

namespace snh::cli {

void add_run_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string scene, out;
    int threads = 0;
    bool resume = false;
    bool keep_going = false;
    bool no_report = false;
    bool force = false;
    bool check = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Runs a scene file (JSON; the keys in docs/scenes.md): backward Euler, BDF2, TR-BDF2 or quasi-static steps of a mesh (a box, a mesh "
      "file, or a rigged model's flesh) with pins, scripted motion, gravity, an initial deformation, contact and colliders, "
      "tissues and muscles (docs/muscles.md). Writes NNN.obj and NNN.vtu frames, frames.pvd, stats.json, stats.csv and the "
      "report (a flesh scene also its surface/, lbs/ and flesh.usda; a scene with muscles muscles.json). Exit code 0 when every step converged, 1 when a step did not converge (the run "
      "stopped there, or went on with --keep-going), 2 for bad input.");
  cmd->add_option("scene", o->scene, "Scene file (.json)")->required();
  cmd->add_option("--out", o->out, "Output directory (default: the scene's output.dir, else output/<scene name>)")->check(non_empty_path());
  cmd->add_flag("--resume", o->resume, "Continue a stopped run in the output directory from its last completed frame");
  cmd->add_flag("--keep-going", o->keep_going,
                "Write a frame that does not converge (marked NOT CONVERGED in its line and in stats.json) and go on from it instead of stopping; the exit code is still 1");
  cmd->add_flag("--no-report", o->no_report, "Do not write the browser report (index.html; snh report DIR writes it later)");
  cmd->add_flag("--force", o->force, "Write into the output directory even if it is not empty and holds no snh run (files with the names of ours are replaced)");
  cmd->add_option("--threads", o->threads, "OpenMP threads for assembly (default: all cores)")->check(CLI::Range(0, 1024));
  cmd->add_flag("--check", o->check,
                "Check the scene and build its mesh (a flesh scene: the volume and the binding): print the sizes and exit "
                "without running or writing anything")
      ->excludes("--resume");
  cmd->callback([o, &exit_code]() {
    if (o->threads > 0) omp_set_num_threads(o->threads);
    BuiltScene built = build_scene(load_scene(o->scene));
    if (!o->out.empty()) built.scene.output.dir = o->out;
    built.scene.run.resume = o->resume;
    built.scene.run.keep_going = o->keep_going;
    built.scene.run.check_only = o->check;
    exit_code = run_scene_command(built, o->no_report, o->force);
  });
}

int run_scene_command(BuiltScene& built, bool no_report, bool force) {
  RunControl& run = built.scene.run;
  run.command_line = invocation();
  run.live_progress = ::isatty(STDOUT_FILENO) != 0;
  if (run.check_only) return run_scene(built, std::cout).all_converged ? 0 : 1;
  install_stop_handlers();
  // The directory stays locked until the report is written: no other run can start there meanwhile.
  const std::filesystem::path out = built.scene.output.dir;
  run.lock = std::make_shared<RunDirectoryLock>(out, force);
  const SceneResult r = run_scene(built, std::cout);
  if (!no_report) (void)write_run_report(out, "snh");
  return r.interrupted_by ? 128 + r.interrupted_by : r.all_converged ? 0 : 1;
}

}  // namespace snh::cli
