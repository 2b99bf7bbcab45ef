// The stability lab, reduced (small meshes, a few energies): each experiment's expected outcome, and
// that an energy that fails (undefined start, Newton failure) is reported rather than crashing.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "snh/setup/lab.hpp"

namespace snh {
namespace {

LabOptions quick(std::vector<std::string> energies, const std::string& name) {
  LabOptions o;
  o.quick = true;
  o.energies = std::move(energies);
  o.out = std::filesystem::temp_directory_path() / ("snh_test_lab_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(o.out);
  return o;
}

const LabRun& get(const std::vector<LabRun>& runs, const std::string& c, const std::string& e) {
  for (const LabRun& r : runs)
    if (r.case_name == c && r.energy == e) return r;
  throw std::runtime_error("no run " + c + " " + e);
}

TEST(Lab, RestStabilitySnhStaysPsiDShrinks) {
  const LabOptions o = quick({"stable_neo_hookean", "psi_d"}, "rest");
  const auto runs = lab_rest(o);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_NEAR(get(runs, "free_cube", "stable_neo_hookean").final_volume, 1.0, 1e-6);
  // docs/math.md §5: at ν = 0.4, psi_d settles near s ≈ 0.897 per axis.
  EXPECT_NEAR(std::cbrt(get(runs, "free_cube", "psi_d").final_volume), 0.897, 0.005);
  EXPECT_TRUE(std::filesystem::exists(o.out / "rest" / "free_cube" / "psi_d" / "stats.json"));
  std::filesystem::remove_all(o.out);
}

TEST(Lab, InversionSnhRecoversLogEnergiesAreReportedUndefined) {
  const LabOptions o = quick({"stable_neo_hookean", "neo_hookean"}, "inversion");
  const auto runs = lab_inversion(o);
  for (const char* c : {"reflected", "pushed_through"}) {
    const LabRun& snh = get(runs, c, "stable_neo_hookean");
    EXPECT_TRUE(snh.recovered()) << c << ": volume " << snh.final_volume << ", inverted " << snh.final_inverted;
    EXPECT_LT(snh.volume.front(), snh.volume.back()) << "it started (partly) inverted";
    const LabRun& log_j = get(runs, c, "neo_hookean");
    EXPECT_FALSE(log_j.defined_at_start) << c;
    EXPECT_FALSE(log_j.converged);
    EXPECT_NE(log_j.failure.find("outside the domain of neo_hookean"), std::string::npos) << log_j.failure;
    for (double v : log_j.volume) EXPECT_TRUE(std::isfinite(v)) << "no NaN anywhere";
  }
  std::filesystem::remove_all(o.out);
}

TEST(Lab, ReflectionSnhDoesNotDependOnTheAxisCorotatedDoes) {
  const LabOptions o = quick({"stable_neo_hookean", "corotated"}, "reflection");
  const auto runs = lab_reflection(o);
  auto spread = [&](const std::string& e) {
    double lo = 1e300, hi = -1e300;
    for (const char* c : {"reflect_x", "reflect_y", "reflect_z"}) {
      const LabRun& r = get(runs, c, e);
      if (!r.converged) return std::numeric_limits<double>::infinity();  // fails on some axes only
      lo = std::min(lo, r.final_volume);
      hi = std::max(hi, r.final_volume);
    }
    return hi - lo;
  };
  EXPECT_LT(spread("stable_neo_hookean"), 1e-4);
  EXPECT_TRUE(get(runs, "reflect_x", "stable_neo_hookean").recovered());
  // Corotated (signed σ, docs/math.md) is not reflection consistent: the outcome depends on the axis, by
  // far more than SNH's solver tolerance (quick: 6.8e-4 against 2.3e-6; the full lab: 2.9e-2).
  EXPECT_GT(spread("corotated"), std::max(1e-4, 100.0 * spread("stable_neo_hookean")));
  for (const char* c : {"reflect_x", "reflect_y", "reflect_z"}) {
    const LabRun& r = get(runs, c, "corotated");
    if (!r.converged) {
      EXPECT_NE(r.failure.find("Newton"), std::string::npos) << "a failure is reported: " << r.failure;
    }
  }
  std::filesystem::remove_all(o.out);
}

TEST(Lab, DegeneracySnhIsTrappedBelowTheTrapSizeTheLogFormIsNot) {
  const LabOptions o = quick({"stable_neo_hookean", "stable_neo_hookean_log"}, "degeneracy");
  EXPECT_NEAR(lab_trap_size(), 0.091, 0.001);  // docs/math.md §5: near μ/(λ+μ) for μ = 1, λ = 10
  const auto runs = lab_degeneracy(o);
  for (const char* e : {"stable_neo_hookean", "stable_neo_hookean_log"}) {
    EXPECT_TRUE(std::isfinite(get(runs, "plane", e).recovery_time)) << e << " recovers from a plane";
    EXPECT_TRUE(std::isfinite(get(runs, "above_trap", e).recovery_time)) << e << " recovers from 2x the trap size";
  }
  const LabRun& trapped = get(runs, "below_trap", "stable_neo_hookean");
  EXPECT_TRUE(trapped.converged);
  EXPECT_LT(std::abs(trapped.final_volume), 1e-3) << "SNH stays collapsed below its trap size";
  EXPECT_TRUE(std::isfinite(get(runs, "below_trap", "stable_neo_hookean_log").recovery_time)) << "the log form has no trap";
  std::filesystem::remove_all(o.out);
}

TEST(Lab, PoissonRatioMatchesWithReparametrization) {
  const LabOptions o = quick({"stable_neo_hookean", "psi_d"}, "poisson");
  const auto rows = lab_poisson(o);
  int checked = 0;
  for (const PoissonRow& r : rows) {
    if (r.energy == "psi_d") {
      EXPECT_FALSE(r.ran);
      EXPECT_FALSE(r.failure.empty());
      continue;
    }
    ASSERT_TRUE(r.ran && std::isfinite(r.measured)) << r.failure;
    if (r.reparametrize) {
      EXPECT_NEAR(r.measured, r.expected, 0.01 * r.expected) << "nu " << r.nu;  // the issue: within 1 %
      ++checked;
    } else if (r.nu == 0.3) {
      EXPECT_LT(r.measured, 0.2) << "without reparametrization SNH is far off at nu = 0.3";
    }
  }
  EXPECT_EQ(checked, 4);
  std::filesystem::remove_all(o.out);
}

TEST(Lab, LargeStretchPreservesVolumeBetterAsNuNearsOneHalf) {
  const LabOptions o = quick({"stable_neo_hookean"}, "stretch");
  const auto rows = lab_stretch(o);
  ASSERT_EQ(rows.size(), 5u);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    ASSERT_TRUE(rows[i].converged) << rows[i].failure;
    if (i > 0) {
      EXPECT_LT(rows[i].volume_ratio, rows[i - 1].volume_ratio) << "nu " << rows[i].nu;
    }
  }
  EXPECT_GT(rows.front().volume_ratio, 1.3);              // nu 0.3: +30 % volume or more
  EXPECT_NEAR(rows.back().volume_ratio, 1.0, 0.02);       // nu 0.495: nearly preserved
  std::filesystem::remove_all(o.out);
}

TEST(Lab, ReportHasEveryTableAndCurve) {
  const LabOptions o = quick({"stable_neo_hookean", "neo_hookean"}, "report");
  const LabReport r = run_lab(o);
  for (const char* key : {"rest", "inversion", "reflection", "degeneracy", "poisson", "stretch", "psi_along_sI"})
    EXPECT_TRUE(r.json.contains(key)) << key;
  EXPECT_EQ(r.json["psi_along_sI"]["s"].size(), r.json["psi_along_sI"]["psi"]["neo_hookean"].size());
  EXPECT_TRUE(r.json["psi_along_sI"]["psi"]["neo_hookean"][0].is_null()) << "psi undefined at s = -0.5";
  EXPECT_FALSE(r.json["degeneracy"][0]["volume"].empty());
  for (const char* title : {"1. Rest", "2. Inversion", "3. Reflection", "4. Degeneracy", "5. Poisson", "6. Large stretch"})
    EXPECT_NE(r.text.find(title), std::string::npos) << title;
  EXPECT_TRUE(std::filesystem::exists(o.out / "lab.json"));
  std::filesystem::remove_all(o.out);
}

}  // namespace
}  // namespace snh
