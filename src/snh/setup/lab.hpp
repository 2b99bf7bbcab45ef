#pragma once
// The stability lab (docs/design.md): the experiments that show, by simulation and for every energy
// side by side, the paper's stability claims (docs/math.md §5) and its Poisson's-ratio argument.
//   rest        a free cube starting at rest: does it stay at its rest volume?
//   inversion   a fully inverted cube, and one with a few elements pushed through: does it recover?
//   reflection  the inverted cube reflected in x, y or z: does the outcome depend on the axis?
//   degeneracy  a cube crushed to a plane, a line, a point, and scaled below / above the trap size of
//               production SNH (docs/math.md §5), then released: does it recover, and how fast?
//   poisson     a bar under 0.1 % uniaxial strain with sliding ends: the measured Poisson's ratio
//   stretch     the paper's stretch test to 3.5×: the volume ratio for ν from 0.3 to 0.495
// Each simulation writes its frames and stats like any run, under OUT/<experiment>/<case>/<energy>.
#include <filesystem>
#include <limits>
#include <ostream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "snh/material/lame.hpp"

namespace snh {

struct LabOptions {
  bool quick = false;                        ///< smaller meshes, shorter times
  std::filesystem::path out = "output/lab";
  std::vector<std::string> energies;         ///< empty: every registered energy
  std::ostream* progress = nullptr;          ///< one line per simulation when set
  std::string command_line;                  ///< for lab.json and the report
};

/// One simulation of an experiment.
struct LabRun {
  std::string experiment, case_name, energy;
  bool defined_at_start = true;   ///< false: the energy is undefined at the starting state (J ≤ 0)
  bool converged = true;          ///< every step converged
  std::string failure;
  double final_volume = std::numeric_limits<double>::quiet_NaN();  ///< volume ratio at the end
  double final_min_J = std::numeric_limits<double>::quiet_NaN();
  int final_inverted = 0;
  double final_elastic_energy = std::numeric_limits<double>::quiet_NaN();
  double recovery_time = std::numeric_limits<double>::quiet_NaN();  ///< first time with volume ratio ≥ 0.99
  std::vector<double> time, volume;  ///< volume ratio over time (frame by frame)
  std::string dir;                   ///< its output directory, relative to LabOptions::out
  /// Recovered: ran to the end, volume within 1 % of the rest volume, no inverted element.
  [[nodiscard]] bool recovered() const;
};

struct PoissonRow {
  std::string energy;
  double nu = 0.0;            ///< the ν the parameters were made from (E = 1)
  bool reparametrize = false;
  bool ran = false;           ///< false: the energy has no reparametrization (see failure)
  double expected = 0.0;      ///< λ/(2(λ+μ)) of the parameters given, = nu
  double measured = std::numeric_limits<double>::quiet_NaN();  ///< −lateral strain / axial strain
  std::string failure;
  std::string dir;            ///< its output directory relative to LabOptions::out ("" if it did not run)
};

struct StretchRow {
  std::string energy;
  double nu = 0.0;
  bool reparametrized = false;
  bool converged = false;
  double volume_ratio = std::numeric_limits<double>::quiet_NaN();  ///< at 3.5×
  std::string failure;
  std::string dir;            ///< its output directory relative to LabOptions::out
};

[[nodiscard]] std::vector<LabRun> lab_rest(const LabOptions& o);
[[nodiscard]] std::vector<LabRun> lab_inversion(const LabOptions& o);
[[nodiscard]] std::vector<LabRun> lab_reflection(const LabOptions& o);
/// The trap size used for the below/above cases: production SNH's barrier along F = sI for μ = 1, λ = 10.
[[nodiscard]] double lab_trap_size();
[[nodiscard]] std::vector<LabRun> lab_degeneracy(const LabOptions& o);
[[nodiscard]] std::vector<PoissonRow> lab_poisson(const LabOptions& o);
[[nodiscard]] std::vector<StretchRow> lab_stretch(const LabOptions& o);

/// ψ(sI) for every energy on a grid of s (null where undefined).
[[nodiscard]] nlohmann::json lab_psi_along_sI(const Lame& p, const std::vector<std::string>& energies);

struct LabReport {
  nlohmann::json json;  ///< the results, the tables ("tables": title, note, columns, rows) and curves (also OUT/lab.json)
  std::string text;     ///< the tables, for a terminal
};

/// Runs every experiment, writes OUT/lab.json and returns the report.
[[nodiscard]] LabReport run_lab(const LabOptions& o);

}  // namespace snh
