// The output directory of a run: the lock, clearing a previous run, the frames a resume keeps, and
// checkpoints that refuse damage (a changed byte, a non-finite state, an older format).
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <algorithm>
#include <functional>
#include <limits>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/box.hpp"
#include "snh/run/checkpoint.hpp"
#include "snh/run/driver.hpp"
#include "snh/run/output.hpp"
#include "snh/run/run_directory.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

fs::path scratch_dir(const std::string& name) {
  fs::path d = test::fresh_dir("snh_test_rundir_", name);
  fs::create_directories(d);
  return d;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(RunDirectory, ALockedDirectoryRefusesASecondRunUntilReleased) {
  const fs::path d = scratch_dir("lock");
  {
    const RunDirectoryLock first(d / "out");  // created by the lock
    EXPECT_TRUE(fs::is_directory(d / "out"));
    const std::string e = error_of([&] { RunDirectoryLock second(d / "out"); });
    EXPECT_EQ(e, fmt::format("another snh run is writing to {} (process {}): wait for it to finish or choose another output "
                             "directory",
                             (d / "out").string(), ::getpid()));
  }
  EXPECT_EQ(error_of([&] { RunDirectoryLock again(d / "out"); }), "") << "released with the first lock";
  std::ofstream(d / "file") << "x";
  EXPECT_NE(error_of([&] { RunDirectoryLock not_a_dir(d / "file"); }).find("exists and is not a directory"), std::string::npos);
  fs::remove_all(d);
}

TEST(RunDirectory, ADirectoryTheLockMadeAndNothingWroteIsRemovedWithIt) {
  const fs::path d = scratch_dir("unused");
  { const RunDirectoryLock lock(d / "new"); }  // a run refused before its first file
  EXPECT_FALSE(fs::exists(d / "new"));
  {
    const RunDirectoryLock lock(d / "used");
    std::ofstream(d / "used" / "000.obj") << "v 0 0 0\n";
  }
  EXPECT_TRUE(fs::exists(d / "used" / "000.obj")) << "a directory with a file of the run stays";
  fs::create_directories(d / "given");
  { const RunDirectoryLock lock(d / "given"); }
  EXPECT_TRUE(fs::is_directory(d / "given")) << "a directory that was there stays";
  fs::remove_all(d);
}

TEST(RunDirectory, ClearingRemovesOnlyWhatARunOfOursWrites) {
  const fs::path d = scratch_dir("clear");
  for (const char* f : {"000.obj", "012.vtu", "1234.obj", "stats.json", "stats.csv", "index.html",
                        "stats.json.tmp.77", ".snh-write-test.5"})
    std::ofstream(d / f) << "x";
  fs::create_directories(d / "report" / "frames");
  std::ofstream(d / "report" / "frames" / "000.js") << "x";
  for (const char* f : {"notes.txt", "12.obj", "mesh.vtu", "my_stats.json", "index.htm"}) std::ofstream(d / f) << "keep";
  fs::create_directories(d / "000.obj.d");
  // No sign of a run of ours yet: the files are someone else's; the directory is refused, nothing is removed
  // and no lock file is left.
  EXPECT_NE(error_of([&] { RunDirectoryLock lock(d); }).find("is not empty and holds no snh run (it has .snh-write-test.5)"),
            std::string::npos);
  EXPECT_TRUE(fs::exists(d / "index.html"));
  EXPECT_FALSE(fs::exists(d / ".snh-lock"));
  std::ofstream(d / "checkpoint.bin") << "x";
  std::ofstream(d / "frames.pvd") << "x";
  // A checkpoint (or frames.pvd) shows a run of ours.
  const RunDirectoryLock lock(d);
  EXPECT_FALSE(lock.found_earlier());
  EXPECT_EQ(clear_previous_run(d, lock), 11);
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(d)) left.push_back(e.path().filename().string());
  std::sort(left.begin(), left.end());
  EXPECT_EQ(left, (std::vector<std::string>{".snh-lock", "000.obj.d", "12.obj", "index.htm", "mesh.vtu", "my_stats.json",
                                            "notes.txt"}));
  fs::remove_all(d);
}

// Inside a flesh run's surface/ and lbs/ and the report's report/, only the files a run writes there go:
// a user's notes and subdirectories stay (they were all deleted before), a subdirectory left empty goes, and
// a directory or FIFO under one of our names is refused before anything is removed.
TEST(RunDirectory, ClearingLeavesWhatIsNotOursInsideItsSubdirectories) {
  const fs::path d = scratch_dir("clear_sub");
  std::ofstream(d / "checkpoint.bin") << "x";
  fs::create_directories(d / "surface" / "sub");
  fs::create_directories(d / "lbs" / "003.obj");
  fs::create_directories(d / "report" / "frames");
  for (const char* f : {"surface/000.obj", "surface/001.obj.tmp.9", "surface/NOTES.txt", "surface/sub/000.obj", "lbs/000.obj",
                        "lbs/003.obj/inside.txt", "report/data.js", "report/snh-report.js", "report/frames/000.js"})
    std::ofstream(d / f) << "x";
  const RunDirectoryLock lock(d);
  // A directory where a frame goes is not ours: refused before anything is removed.
  EXPECT_NE(error_of([&] { (void)clear_previous_run(d, lock); }).find("lbs/003.obj: is a directory"), std::string::npos);
  EXPECT_TRUE(fs::exists(d / "surface" / "000.obj"));
  fs::rename(d / "lbs" / "003.obj", d / "lbs" / "kept");
  EXPECT_EQ(clear_previous_run(d, lock), 7);  // checkpoint.bin, 2 in surface/, 1 in lbs/, 3 in report/
  EXPECT_TRUE(fs::exists(d / "surface" / "NOTES.txt"));
  EXPECT_TRUE(fs::exists(d / "surface" / "sub" / "000.obj"));
  EXPECT_FALSE(fs::exists(d / "surface" / "000.obj"));
  EXPECT_FALSE(fs::exists(d / "surface" / "001.obj.tmp.9"));
  EXPECT_TRUE(fs::exists(d / "lbs" / "kept" / "inside.txt"));
  EXPECT_FALSE(fs::exists(d / "lbs" / "000.obj"));
  EXPECT_FALSE(fs::exists(d / "report")) << "report/ held only ours: removed, frames/ with it";
  ASSERT_EQ(::mkfifo((d / "flesh.usda").c_str(), 0600), 0);
  std::ofstream(d / "stats.json") << "x";
  EXPECT_NE(error_of([&] { (void)clear_previous_run(d, lock); }).find("flesh.usda: is a FIFO"), std::string::npos);
  EXPECT_TRUE(fs::exists(d / "stats.json"));
  fs::remove_all(d);
}

// The frame where a run stops without converging is written as failed_NNN, outside the series; a frame written
// later under that index (a resumed run that gets past it) removes it. A frame that did not converge but stays
// in the series (a run that went past it) is marked in frames.pvd by its note.
TEST(FrameWriter, AFailedFrameIsKeptOutOfTheSeriesAndANoteMarksAFrameInIt) {
  const fs::path d = scratch_dir("failed_frame");
  const VolumeMesh mesh = box_hexes(1);
  const ElasticTerm elastic(mesh, make_material("stable_neo_hookean", {1.0, 10.0}));
  const Eigen::VectorXd x = test::flatten(mesh.vertices);
  const ElasticTerm::Deformation def = elastic.deformation(x);
  FrameWriter frames(d, mesh, true, std::vector<bool>(mesh.vertex_count(), false));
  frames.write(0, 0.0, x, def);
  frames.write(1, 0.5, x, def, kFailedPrefix);
  frames.write_series();
  EXPECT_TRUE(fs::exists(d / "failed_001.obj"));
  EXPECT_TRUE(fs::exists(d / "failed_001.vtu"));
  EXPECT_FALSE(fs::exists(d / "001.obj"));
  const std::string text = test::file_text(d / "frames.pvd");
  EXPECT_EQ(text.find("failed_"), std::string::npos) << text;
  EXPECT_EQ(read_pvd(d / "frames.pvd").size(), 1u);
  frames.write(1, 0.5, x, def, "", "frame 1 did not converge -- twice");
  frames.write_series();
  EXPECT_FALSE(fs::exists(d / "failed_001.obj"));
  EXPECT_FALSE(fs::exists(d / "failed_001.vtu"));
  const std::string text2 = test::file_text(d / "frames.pvd");
  EXPECT_NE(text2.find("<!-- frame 1 did not converge - twice -->\n<DataSet timestep=\"0.5\""), std::string::npos) << text2;
  EXPECT_EQ(read_pvd(d / "frames.pvd").size(), 2u);
  fs::remove_all(d);
}

// The warning of frames that converged inside out counts solved frames only: not the initial state (frame 0, which a
// lab case starts inverted), nor a frame that did not converge (its failure says more).
TEST(RunOutcome, FramesInsideOutCountSolvedConvergedFramesOnly) {
  auto record = [](int index, int inverted, bool converged) {
    StepRecord r;
    r.index = index, r.inverted = inverted, r.converged = converged;
    return r;
  };
  const InsideOut io = inside_out_frames({record(0, 9, true), record(1, 2, true), record(2, 7, false), record(3, 4, true),
                                          record(4, 0, true), record(5, 4, true)});
  EXPECT_EQ(io.frames, 3);
  EXPECT_EQ(io.most, 4);
  EXPECT_EQ(io.worst, 3);
  EXPECT_EQ(inside_out_frames({record(0, 9, true)}).frames, 0);
}

TEST(RunDirectory, ForceWritesIntoADirectoryOfSomeoneElse) {
  const fs::path d = scratch_dir("force");
  std::ofstream(d / "notes.txt") << "keep";
  std::ofstream(d / "index.html") << "theirs";
  const RunDirectoryLock lock(d, true);
  EXPECT_TRUE(lock.forced());
  EXPECT_EQ(clear_previous_run(d, lock), 1);
  EXPECT_TRUE(fs::exists(d / "notes.txt"));
  fs::remove_all(d);
}

TEST(RunDirectory, AStatsFileOfOursIsReadOnlyIfRegular) {
  const fs::path d = scratch_dir("fifo");
  ASSERT_EQ(::mkfifo((d / "stats.json").c_str(), 0644), 0);  // opening it to read would block
  EXPECT_FALSE(holds_a_run_of_ours(d));
  EXPECT_NE(error_of([&] { RunDirectoryLock lock(d); }).find("holds no snh run (it has stats.json)"), std::string::npos);
  fs::remove_all(d);
}

TEST(RunDirectory, AStatsFileOfSnhShowsARunOfOurs) {
  const fs::path d = scratch_dir("ours");
  std::ofstream(d / "stats.json") << "{\"snh_version\": \"0.1.0\", \"steps\": []}";  // a run from before the lock file
  std::ofstream(d / "001.obj") << "x";
  const RunDirectoryLock lock(d);
  EXPECT_EQ(clear_previous_run(d, lock), 2);
  fs::remove_all(d);
}

TEST(RunDirectory, AResumeNeedsTheFramesItKeeps) {
  const fs::path d = scratch_dir("frames");
  for (int i = 0; i <= 3; ++i)
    for (const char* ext : {"obj", "vtu"}) std::ofstream(d / fmt::format("{:03d}.{}", i, ext)) << "x";
  EXPECT_EQ(error_of([&] { check_kept_frames(d, 3, true); }), "");
  fs::remove(d / "002.vtu");
  EXPECT_EQ(error_of([&] { check_kept_frames(d, 3, false); }), "") << "no .vtu frames asked for";
  EXPECT_EQ(error_of([&] { check_kept_frames(d, 3, true); }),
            fmt::format("cannot resume: {} is missing (the run being resumed wrote frames 000 to 003); start the run again "
                        "without --resume",
                        (d / "002.vtu").string()));
  fs::remove_all(d);
}

TEST(Checkpoint, RoundTripsAndRefusesDamage) {
  const fs::path d = scratch_dir("checkpoint");
  const Checkpoint c{.fingerprint = "stretch: test", .step = 7, .time = 0.35, .x = Eigen::VectorXd::LinSpaced(30, -1, 2),
                     .aux = Eigen::VectorXd::Constant(30, 0.5)};
  write_checkpoint(d, c);
  const std::optional<Checkpoint> back = read_checkpoint(d);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->fingerprint, c.fingerprint);
  EXPECT_EQ(back->step, 7);
  EXPECT_EQ(back->time, 0.35);
  EXPECT_EQ(back->x, c.x);
  EXPECT_EQ(back->aux, c.aux);
  EXPECT_EQ(checkpoint_for_resume(d, c.fingerprint, 30).step, 7);
  EXPECT_NE(error_of([&] { (void)checkpoint_for_resume(d, "other", 30); }).find("used other settings (stretch: test; now other)"),
            std::string::npos);

  // Every single changed byte is found (the checksum covers the whole file).
  std::string bytes;
  {
    std::ifstream in(d / "checkpoint.bin", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  int refused = 0;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::string flipped = bytes;
    flipped[i] = static_cast<char>(flipped[i] ^ 0x10);
    std::ofstream(d / "checkpoint.bin", std::ios::binary) << flipped;
    if (!error_of([&] { (void)read_checkpoint(d); }).empty()) ++refused;
  }
  EXPECT_EQ(refused, static_cast<int>(bytes.size()));
  std::ofstream(d / "checkpoint.bin", std::ios::binary) << bytes.substr(0, bytes.size() - 3);
  EXPECT_NE(error_of([&] { (void)read_checkpoint(d); }).find("damaged checkpoint"), std::string::npos);
  std::ofstream(d / "checkpoint.bin", std::ios::binary) << "SNHCKPT1" << bytes.substr(8);
  EXPECT_NE(error_of([&] { (void)read_checkpoint(d); }).find("written by an older snh without a checksum"), std::string::npos);

  // A state that is not finite is refused even with a valid checksum.
  Checkpoint nan = c;
  nan.x[4] = std::numeric_limits<double>::quiet_NaN();
  write_checkpoint(d, nan);
  EXPECT_EQ(error_of([&] { (void)read_checkpoint(d); }),
            (d / "checkpoint.bin").string() + ": damaged checkpoint (its state is not finite)");
  // Nor a time that is not finite or negative (a resumed run would carry it into every frame).
  for (const double t : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -1.0}) {
    Checkpoint bad_time = c;
    bad_time.time = t;
    write_checkpoint(d, bad_time);
    EXPECT_EQ(error_of([&] { (void)read_checkpoint(d); }), (d / "checkpoint.bin").string() + ": damaged checkpoint (bad time)") << t;
  }
  // Empty vectors round trip (reading them copied 0 bytes to a null pointer: undefined, found by fuzz_checkpoint
  // under UBSan).
  Checkpoint empty = c;
  empty.x.resize(0);
  empty.aux.resize(0);
  write_checkpoint(d, empty);
  ASSERT_TRUE(read_checkpoint(d));
  EXPECT_EQ(read_checkpoint(d)->x.size(), 0);
  // A fingerprint with control bytes is echoed on one line, escaped (fuzz_checkpoint aborts on a line break).
  Checkpoint odd = c;
  odd.fingerprint = "two\nlines\x01";
  write_checkpoint(d, odd);
  EXPECT_NE(error_of([&] { (void)checkpoint_for_resume(d, "other", 30); }).find("used other settings (two\\x0alines\\x01; now other)"),
            std::string::npos);
  fs::remove_all(d);
}

}  // namespace
}  // namespace snh
