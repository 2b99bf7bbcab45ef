// The paper's stretch test at res 4: convergence at every step, symmetry, thinning of the middle,
// quadratic convergence of Newton near the solution, and the OBJ frames' structure.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <csignal>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/mesh_write.hpp"
#include "snh/mesh/box.hpp"
#include "snh/run/checkpoint.hpp"
#include "snh/run/interrupt.hpp"
#include "snh/setup/stretch.hpp"
#include "test_support.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;

fs::path stretch_dir(const std::string& name) { return test::fresh_dir("snh_test_", name); }

/// Vertex positions from an OBJ frame ("v x y z" lines), and the count of "f" lines.
Eigen::Matrix3Xd read_obj_vertices(const fs::path& path, int* faces = nullptr) {
  std::ifstream in(path);
  std::vector<Eigen::Vector3d> v;
  int f = 0;
  std::string tag;
  for (std::string line; std::getline(in, line);) {
    std::istringstream s(line);
    s >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      s >> p[0] >> p[1] >> p[2];
      v.push_back(p);
    } else if (tag == "f") {
      ++f;
    }
  }
  if (faces) *faces = f;
  Eigen::Matrix3Xd out(3, v.size());
  for (std::size_t i = 0; i < v.size(); ++i) out.col(i) = v[i];
  return out;
}

StretchResult run(CellType element, const fs::path& out, double tolerance, int steps = 25, double stretch = 3.5,
                  TetSplit split = TetSplit::paper) {
  StretchConfig c;
  c.element = element;
  c.tet_split = split;
  c.resolution = 4;
  c.steps = steps;
  c.stretch = stretch;
  c.out = out;
  c.newton.tolerance = tolerance;
  std::ostringstream log;
  return run_stretch(c, log);
}

/// Largest mismatch of the lattice positions X under each symmetry of the stretch test.
struct Symmetry {
  double mirror_x = 0, mirror_z = 0, inversion = 0, swap_xz = 0;
};
Symmetry measure_symmetry(const Eigen::Matrix3Xd& X, int res) {
  Symmetry m;
  for (int k = 0; k <= res; ++k)
    for (int j = 0; j <= res; ++j)
      for (int i = 0; i <= res; ++i) {
        const Eigen::Vector3d p = X.col(lattice_index(res, i, j, k));
        const Eigen::Vector3d mx = X.col(lattice_index(res, res - i, j, k));
        const Eigen::Vector3d mz = X.col(lattice_index(res, i, j, res - k));
        const Eigen::Vector3d inv = X.col(lattice_index(res, res - i, res - j, res - k));
        const Eigen::Vector3d sw = X.col(lattice_index(res, k, j, i));
        m.mirror_x = std::max(m.mirror_x, (p - Eigen::Vector3d(-mx[0], mx[1], mx[2])).norm());
        m.mirror_z = std::max(m.mirror_z, (p - Eigen::Vector3d(mz[0], mz[1], -mz[2])).norm());
        m.inversion = std::max(m.inversion, (p + inv).norm());
        m.swap_xz = std::max(m.swap_xz, (p - Eigen::Vector3d(sw[2], sw[1], sw[0])).norm());
      }
  return m;
}

/// Every step converged to the paper's ‖f‖² < 1e-6 with no inverted element.
void expect_every_step_converged(const StretchResult& r) {
  ASSERT_TRUE(r.all_converged);
  ASSERT_EQ(r.steps.size(), 25u);
  for (const auto& s : r.steps) {
    EXPECT_TRUE(s.converged);
    EXPECT_LT(s.residual * s.residual, 1e-6);  // the paper's ‖f‖² < 1e-6
    EXPECT_GT(s.min_J, 0.0);
    EXPECT_EQ(s.inverted, 0);
  }
}

class Stretch : public ::testing::TestWithParam<CellType> {};

// The paper's test at res 4: every step converges, the middle thins, and the solution has the
// symmetries of the mesh. Symmetric vertices agree to 1e-6 (OBJ values carry 10 significant digits;
// Newton stops at ‖f‖ < 1e-3, so rounding differences between symmetric vertices are not corrected and
// the extrapolated guesses carry them on for 25 steps: about 1e-8 measured). A mesh that lacks a
// symmetry is off by about 0.5.
TEST_P(Stretch, ConvergesEveryStepThinsInTheMiddleAndIsSymmetric) {
  const fs::path out = stretch_dir(std::string(to_string(GetParam())) + "_paper");
  const StretchResult r = run(GetParam(), out, 1e-3);
  expect_every_step_converged(r);
  EXPECT_LT(r.middle_width, 1.5);  // from 2 at rest; ≈ 1.01 at res 4, ≈ 1.06 at res 10 (docs/paper-programs.md)
  EXPECT_GT(r.middle_width, 0.5);
  EXPECT_TRUE(fs::exists(out / "stats.json"));
  EXPECT_TRUE(fs::exists(out / "stats.csv"));
  const Symmetry m = measure_symmetry(read_obj_vertices(out / "025.obj"), 4);
  if (GetParam() == CellType::hex8) {
    EXPECT_LT(m.mirror_x, 1e-6);
    EXPECT_LT(m.mirror_z, 1e-6);
  } else {
    // The paper's 6-tet split around each cell's c0–c7 diagonal is not mirror symmetric, but it is
    // symmetric under central inversion and under exchanging x and z: those hold exactly. The mirror
    // mismatch is a discretization effect of that split (0.51 at res 4, 0.14 at res 10); with the
    // mirrored split (next test) the mirrors hold exactly.
    EXPECT_LT(m.inversion, 1e-6);
    EXPECT_LT(m.swap_xz, 1e-6);
    EXPECT_GT(m.mirror_x, 1e-2);
    std::cout << "tet mirror mismatch " << m.mirror_x << ", inversion " << m.inversion << ", x-z swap " << m.swap_xz << "\n";
  }
  fs::remove_all(out);
}

TEST(StretchMeshFile, NoMiddleCrossSectionIsReportedAsNotApplicable) {
  // Issue 13: a mesh whose layer nearest the middle is one vertex (a single tet) or the pinned end layer
  // (the res-1 box) reported "width 0 (rest 0)" or the pinned layer's width; now NaN, null and "n/a".
  const fs::path dir = stretch_dir("no_middle");
  fs::create_directories(dir);
  VolumeMesh tet;
  tet.type = CellType::tet4;
  tet.vertices.resize(3, 4);
  tet.vertices << 0, 1, 0, 0.3, 0, 0, 1, 0.4, 0, 0, 0, 1;
  tet.cells.resize(4, 1);
  tet.cells << 0, 1, 2, 3;
  write_msh(dir / "tet.msh", tet);
  for (const bool single_tet : {true, false}) {
    StretchConfig c;
    c.resolution = 1;
    c.steps = 1;
    c.stretch = 1.1;
    c.out = dir / (single_tet ? "tet" : "box");
    if (single_tet) c.mesh_file = dir / "tet.msh";
    std::ostringstream log;
    const StretchResult r = run_stretch(c, log);
    EXPECT_TRUE(std::isnan(r.middle_width)) << r.middle_width;
    EXPECT_NE(log.str().find("middle cross-section n/a"), std::string::npos) << log.str();
    std::ifstream in(c.out / "stats.json");
    const nlohmann::json stats = nlohmann::json::parse(in);
    EXPECT_TRUE(stats.at("middle_width").is_null());
  }
  fs::remove_all(dir);
}

TEST(StretchMeshFile, AMeshFileOfTheBoxGivesTheBoxResultAndAnyAxisWorks) {
  // The res-4 box written as Gmsh 4.1 and stretched as a mesh file: the same run as the box.
  const fs::path dir = stretch_dir("mesh_file");
  fs::create_directories(dir);
  for (CellType type : {CellType::tet4, CellType::hex8}) {
    write_msh(dir / "box.msh", type == CellType::tet4 ? box_tets(4) : box_hexes(4));
    StretchConfig box;
    box.element = type;
    box.resolution = 4;
    box.steps = 5;
    box.stretch = 2.0;
    box.out = dir / "box";
    StretchConfig file = box;
    file.mesh_file = dir / "box.msh";
    file.out = dir / "file";
    std::ostringstream log;
    const StretchResult a = run_stretch(box, log), b = run_stretch(file, log);
    ASSERT_TRUE(a.all_converged && b.all_converged);
    EXPECT_EQ(a.middle_width, b.middle_width) << to_string(type);
    EXPECT_EQ(a.steps.back().energy, b.steps.back().energy) << to_string(type);
    EXPECT_EQ(b.middle_rest_width, 2.0);
  }
  // Hexes stretched along x and along z: the y-stretch's answers (the hex box is symmetric).
  StretchConfig y;
  y.element = CellType::hex8;
  y.resolution = 4;
  y.steps = 5;
  y.stretch = 2.0;
  y.out = dir / "y";
  std::ostringstream log;
  const StretchResult ry = run_stretch(y, log);
  for (int axis : {0, 2}) {
    StretchConfig c = y;
    c.axis = axis;
    c.out = dir / ("axis" + std::to_string(axis));
    const StretchResult r = run_stretch(c, log);
    ASSERT_TRUE(r.all_converged);
    EXPECT_NEAR(r.middle_width, ry.middle_width, 1e-9) << "axis " << axis;
    EXPECT_NEAR(r.steps.back().energy, ry.steps.back().energy, 1e-9 * ry.steps.back().energy);
  }
  fs::remove_all(dir);
}

TEST(StretchInterrupt, AStopKeepsTheCompletedStepsAndTheirFrames) {
  const fs::path full_dir = stretch_dir("int_full"), cut_dir = stretch_dir("int_cut");
  StretchConfig c;
  c.element = CellType::hex8;
  c.resolution = 3;
  c.steps = 8;
  c.out = full_dir;
  std::ostringstream log;
  const StretchResult full = run_stretch(c, log);
  ASSERT_TRUE(full.all_converged);
  // Ask to stop (as SIGTERM would) at the 6th Newton iteration, in the middle of a step.
  int calls = 0;
  c.newton.on_iteration = [&](int, double) {
    if (++calls == 6) request_stop(SIGTERM);
  };
  c.out = cut_dir;
  const StretchResult cut = run_stretch(c, log);
  request_stop(0);
  EXPECT_EQ(cut.interrupted_by, SIGTERM);
  EXPECT_FALSE(cut.all_converged);
  const std::size_t done = cut.steps.size();
  ASSERT_GT(done, 0u);
  ASSERT_LT(done, 8u);
  const std::string last = fmt::format("{:03d}.obj", done), next = fmt::format("{:03d}.obj", done + 1);
  EXPECT_TRUE(fs::exists(cut_dir / last));
  EXPECT_FALSE(fs::exists(cut_dir / next)) << "the abandoned step wrote no frame";
  EXPECT_EQ(read_obj_vertices(cut_dir / last), read_obj_vertices(full_dir / last)) << "completed frames are the full run's";
  std::ifstream stats(cut_dir / "stats.json");
  const std::string text((std::istreambuf_iterator<char>(stats)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"interrupted_by_signal\": 15"), std::string::npos);
  EXPECT_NE(log.str().find("INTERRUPTED by signal 15"), std::string::npos);
  fs::remove_all(full_dir);
  fs::remove_all(cut_dir);
}

TEST(StretchInterrupt, ResumeContinuesFromTheLastCompletedStep) {
  const fs::path full_dir = stretch_dir("resume_full"), dir = stretch_dir("resume");
  StretchConfig c;
  c.element = CellType::tet4;
  c.resolution = 4;
  c.steps = 10;
  c.stretch = 2.5;
  c.out = full_dir;
  std::ostringstream log;
  const StretchResult full = run_stretch(c, log);
  ASSERT_TRUE(full.all_converged);
  int calls = 0;
  c.newton.on_iteration = [&](int, double) {
    if (++calls == 9) request_stop(SIGINT);
  };
  c.out = dir;
  const StretchResult cut = run_stretch(c, log);
  request_stop(0);
  ASSERT_EQ(cut.interrupted_by, SIGINT);
  const std::size_t done = cut.steps.size();
  ASSERT_LT(done, 10u);
  // Resuming with other settings is refused, with a message naming both.
  StretchConfig other = c;
  other.newton.on_iteration = nullptr;
  other.resume = true;
  other.stretch = 3.0;
  try {
    (void)run_stretch(other, log);
    ADD_FAILURE() << "resumed with another stretch";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("used other settings"), std::string::npos) << e.what();
  }
  StretchConfig again = c;
  again.newton.on_iteration = nullptr;
  again.resume = true;
  const StretchResult resumed = run_stretch(again, log);
  ASSERT_TRUE(resumed.all_converged);
  ASSERT_EQ(resumed.steps.size(), 10u) << "the history before the stop is kept";
  EXPECT_EQ(resumed.steps[0].newton_iterations, full.steps[0].newton_iterations);
  // The same answer as the uninterrupted run, to the solver tolerance (the resumed run starts with a
  // fresh factorization where the other reused one, so the last bits differ).
  const Eigen::Matrix3Xd a = read_obj_vertices(full_dir / "010.obj"), b = read_obj_vertices(dir / "010.obj");
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_NEAR(resumed.middle_width, full.middle_width, 1e-4);
  for (int s = 0; s <= 10; ++s) EXPECT_TRUE(fs::exists(dir / fmt::format("{:03d}.vtu", s)));
  std::ifstream pvd(dir / "frames.pvd");
  const std::string series((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  EXPECT_NE(series.find("000.vtu"), std::string::npos) << "the series lists the frames from before the stop";
  EXPECT_NE(series.find("010.vtu"), std::string::npos);
  fs::remove_all(full_dir);
  fs::remove_all(dir);
}

/// What a run's progress on disk says while it goes on: the step records in stats.json, its status, the checkpoint's step (-1: none) and the frames frames.pvd lists.
struct Progress {
  std::size_t records = 0;
  std::string status;
  int checkpoint = -1;
  int listed = 0;
};
Progress progress_of(const fs::path& dir) {
  Progress p;
  std::ifstream stats(dir / "stats.json");
  const nlohmann::json j = nlohmann::json::parse(stats);
  p.records = j.at("steps").size();
  p.status = j.at("status");
  if (const auto c = read_checkpoint(dir)) p.checkpoint = c->step;
  std::ifstream pvd(dir / "frames.pvd");
  for (std::string line; std::getline(pvd, line);) p.listed += line.find("<DataSet") != std::string::npos;
  return p;
}

/// A 4-step tet run at res 2 into dir, its progress written every `interval` seconds.
StretchConfig small_run(const fs::path& dir, double interval) {
  StretchConfig c;
  c.element = CellType::tet4;
  c.resolution = 2;
  c.steps = 4;
  c.stretch = 1.5;
  c.out = dir;
  c.progress_interval = interval;
  return c;
}

// The progress (stats.json, stats.csv, frames.pvd, checkpoint.bin) is written after the first step, then
// once progress_interval has passed, and at the end; with an interval of 0, after every step. Seen from
// Newton's first iteration of every step: what the run has left on disk by then.
TEST(StretchProgress, WrittenAfterTheFirstStepThenByTimeAndAtTheEnd) {
  for (const double interval : {0.0, 1e9}) {
    const fs::path dir = stretch_dir("progress");
    StretchConfig c = small_run(dir, interval);
    std::vector<Progress> seen;  // at the start of steps 1 … 4
    c.newton.on_iteration = [&](int iteration, double) {
      if (iteration == 0) seen.push_back(progress_of(dir));
    };
    std::ostringstream log;
    ASSERT_TRUE(run_stretch(c, log).all_converged) << log.str();
    ASSERT_EQ(seen.size(), 4u);
    for (int step = 1; step <= 4; ++step) {
      const Progress& p = seen[step - 1];
      const int saved = step == 1 ? 0 : interval == 0.0 ? step - 1 : 1;  // the last step whose progress is on disk
      EXPECT_EQ(p.status, "running") << "interval " << interval << ", step " << step;
      EXPECT_EQ(p.records, static_cast<std::size_t>(saved)) << "interval " << interval << ", step " << step;
      EXPECT_EQ(p.checkpoint, step == 1 ? -1 : saved) << "interval " << interval << ", step " << step;
      EXPECT_EQ(p.listed, step == 1 ? 0 : saved + 1) << "interval " << interval << ", step " << step;
    }
    const Progress end = progress_of(dir);
    EXPECT_EQ(end.status, "finished");
    EXPECT_EQ(end.records, 4u);
    EXPECT_EQ(end.checkpoint, 4);
    EXPECT_EQ(end.listed, 5);
    fs::remove_all(dir);
  }
}

// A run ended by an exception (here one thrown from Newton's callback in step 3, as a solver's error or
// a frame that cannot be written would be) first writes the progress it had not written: steps 1 and 2
// are in the stats, the series and the checkpoint, and --resume continues from step 2.
TEST(StretchProgress, AnExceptionWritesTheProgressNotYetWritten) {
  const fs::path dir = stretch_dir("progress_throw");
  StretchConfig c = small_run(dir, 1e9);
  int step = 0;
  c.newton.on_iteration = [&](int iteration, double) {
    if (iteration == 0 && ++step == 3) throw std::runtime_error("boom");
  };
  std::ostringstream log;
  EXPECT_THROW((void)run_stretch(c, log), std::runtime_error);
  const Progress p = progress_of(dir);
  EXPECT_EQ(p.status, "running");
  EXPECT_EQ(p.records, 2u);
  EXPECT_EQ(p.checkpoint, 2);
  EXPECT_EQ(p.listed, 3);
  c.newton.on_iteration = nullptr;
  c.resume = true;
  log.str("");
  EXPECT_TRUE(run_stretch(c, log).all_converged);
  EXPECT_NE(log.str().find("resuming after step 2"), std::string::npos) << log.str();
  EXPECT_EQ(progress_of(dir).records, 4u);
  fs::remove_all(dir);
}

TEST(StretchFailure, ANonConvergedStepIsReportedWithItsWorstElement) {
  // Corotated's linear volume term drives the lateral singular values negative at res 4 (docs/results.md).
  const fs::path dir = stretch_dir("corotated");
  StretchConfig c;
  c.resolution = 4;
  c.material = "corotated";
  c.out = dir;
  std::ostringstream log;
  const StretchResult r = run_stretch(c, log);
  ASSERT_FALSE(r.all_converged);
  const StepStats& last = r.steps.back();
  EXPECT_FALSE(last.converged);
  EXPECT_NE(last.failure.find("no convergence in 50 Newton iterations"), std::string::npos) << last.failure;
  EXPECT_NE(last.failure.find("; worst element "), std::string::npos) << last.failure;
  EXPECT_TRUE(fs::exists(dir / fmt::format("failed_{:03d}.obj", last.index))) << "the failed step's state is kept, as no result";
  EXPECT_FALSE(fs::exists(dir / fmt::format("{:03d}.obj", last.index)));
  EXPECT_NE(log.str().find(fmt::format("STOPPED: a step did not converge (its last iterate: failed_{:03d}.obj)", last.index)),
            std::string::npos) << log.str();
  EXPECT_TRUE(fs::exists(dir / "stats.json"));
  fs::remove_all(dir);
}

TEST(StretchMirroredTets, ConvergesEveryStepAndIsMirrorSymmetricInXAndZ) {
  const fs::path out = stretch_dir("tet_mirrored");
  const StretchResult r = run(CellType::tet4, out, 1e-3, 25, 3.5, TetSplit::mirrored);
  expect_every_step_converged(r);
  EXPECT_LT(r.middle_width, 1.5);
  const Symmetry m = measure_symmetry(read_obj_vertices(out / "025.obj"), 4);
  EXPECT_LT(m.mirror_x, 1e-6);
  EXPECT_LT(m.mirror_z, 1e-6);
  fs::remove_all(out);
}

TEST_P(Stretch, NewtonConvergesQuadratically) {
  const fs::path out = stretch_dir(std::string(to_string(GetParam())) + "_quad");
  const StretchResult r = run(GetParam(), out, 1e-11, 1, 2.5);  // one big step, solved tightly
  ASSERT_TRUE(r.all_converged);
  const std::vector<double>& h = r.steps[0].residuals;
  std::ostringstream os;
  os << std::scientific << std::setprecision(2);
  for (double v : h) os << v << " ";
  const std::string seq = os.str();
  ASSERT_GE(h.size(), 4u) << seq;
  // From |g| < 0.1 on: r_{k+1} <= 10 r_k² (quadratic), until the residual reaches rounding level.
  int checked = 0;
  for (std::size_t k = 0; k + 1 < h.size(); ++k) {
    if (h[k] >= 0.1 || h[k + 1] < 1e-12) continue;
    EXPECT_LE(h[k + 1], 10.0 * h[k] * h[k]) << "residuals: " << seq;
    ++checked;
  }
  EXPECT_GE(checked, 2) << "residuals: " << seq;
  std::cout << "residual sequence (" << to_string(GetParam()) << "): " << seq << "\n";
  fs::remove_all(out);
}

TEST_P(Stretch, ObjFramesHaveThePaperStructure) {
  const fs::path out = stretch_dir(std::string(to_string(GetParam())) + "_obj");
  const StretchResult r = run(GetParam(), out, 1e-3, 3, 1.3);
  ASSERT_TRUE(r.all_converged);
  const int res = 4;
  for (int s = 0; s <= 3; ++s) {
    char name[16];
    std::snprintf(name, sizeof name, "%03d.obj", s);
    ASSERT_TRUE(fs::exists(out / name)) << name;
    // Lines: all "v" first, then all "f", 1-based indices within range.
    std::ifstream in(out / name);
    int v = 0, f = 0;
    bool seen_f = false;
    for (std::string line; std::getline(in, line);) {
      std::istringstream ls(line);
      std::string tag;
      ls >> tag;
      if (tag == "v") {
        EXPECT_FALSE(seen_f) << "vertex after faces in " << name;
        ++v;
      } else {
        ASSERT_EQ(tag, "f") << line;
        seen_f = true;
        int a, b, c;
        ls >> a >> b >> c;
        EXPECT_TRUE(a >= 1 && b >= 1 && c >= 1 && a <= v && b <= v && c <= v) << line;
        ++f;
      }
    }
    EXPECT_EQ(v, (res + 1) * (res + 1) * (res + 1));
    EXPECT_EQ(f, 6 * 2 * res * res);  // two triangles per boundary quad
  }
  // Frame 000 is the rest lattice in index order; the pulled layers sit at y = ∓(1 + 0.1 s) for stretch 1.3, 3 steps.
  const Eigen::Matrix3Xd rest = read_obj_vertices(out / "000.obj");
  EXPECT_LT((rest - box_lattice(res)).cwiseAbs().maxCoeff(), 1e-9);
  const Eigen::Matrix3Xd last = read_obj_vertices(out / "003.obj");
  EXPECT_NEAR(last(1, lattice_index(res, 2, 0, 3)), -1.3, 1e-9);
  EXPECT_NEAR(last(1, lattice_index(res, 1, res, 0)), 1.3, 1e-9);
  EXPECT_NEAR(last(0, lattice_index(res, 1, res, 0)), -0.5, 1e-9);  // x held
  fs::remove_all(out);
}

INSTANTIATE_TEST_SUITE_P(Elements, Stretch, ::testing::Values(CellType::tet4, CellType::hex8),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(StretchConfig, RejectsBadInputBeforeAnyWork) {
  StretchConfig c;
  c.out = stretch_dir("reject");
  c.material = "stable_neohookean";
  EXPECT_THROW(validate(c), std::invalid_argument);
  c.material = "stable_neo_hookean";
  c.resolution = 0;
  EXPECT_THROW(validate(c), std::invalid_argument);
  c.resolution = 4;
  c.params = {-1.0, 10.0};
  EXPECT_THROW(validate(c), ParameterError);
  EXPECT_FALSE(fs::exists(c.out / "000.obj"));
  fs::remove_all(c.out);
}

}  // namespace
}  // namespace snh
