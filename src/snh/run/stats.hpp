#pragma once
// What a run records per step (the stretch test) or frame (a scene), described once (docs/design.md):
// a RecordTable lists each record's fields with their JSON key, CSV format, label and plot, and drives
// stats.json, stats.csv, the history read back by --resume, and the column list the report plots from
// (stats.json's "schema"). A new field is one line in a table.
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

namespace snh {

/// Everything recorded about one step or frame; each table writes the fields it lists.
struct StepRecord {
  int index = 0;                ///< step (stretch, from 1) or frame (scene, from 0)
  double time = 0.0;
  int substeps = 0;             ///< time steps made (more than planned where a failed one was retried in halves)
  int halvings = 0;             ///< steps retried in halves after a failed solve (not in the tables: see substeps)
  bool converged = true;
  int newton_iterations = 0, line_search_steps = 0, linear_iterations = 0, factorizations = 0;
  int true_hessian_steps = 0;   ///< Newton iterations that used the unprojected Hessian
  double residual = 0.0;        ///< final ‖g‖ (the largest of the substeps)
  /// ‖d‖∞ of the last complete Newton direction (the largest of the substeps): how far the solve still was
  /// from its answer (NewtonReport::last_step)
  double newton_step = 0.0;
  double energy = 0.0;          ///< the minimised energy at the end (stretch: elastic)
  double elastic_energy = 0.0, kinetic_energy = 0.0, gravity_energy = 0.0;
  double total_energy = 0.0;    ///< elastic + kinetic + gravity
  double wall_seconds = 0.0, assembly_seconds = 0.0, solve_seconds = 0.0;
  double min_J = 1.0;           ///< smallest det F over all quadrature points
  int inverted = 0;             ///< elements with det F ≤ 0 somewhere
  double volume_ratio = 1.0;    ///< deformed / rest volume
  double surface_volume_ratio = 1.0;  ///< flesh: the volume inside the embedded render surface / at rest
  double lbs_volume_ratio = 1.0;      ///< flesh: the same for the surface posed by linear blend skinning
  double lbs_distance = 0.0;          ///< flesh: the largest distance of a render-surface vertex from its skinned place
  double tip_distance = 0.0;          ///< flesh: the same over the skin vertices nearest the skeleton's end joints
  // Contact (runs with contact terms; contact_table): at the frame's solution, and during its solve.
  int contact_pairs = 0;              ///< active pairs (self-contact pairs and points near a plane)
  double min_contact_distance = 0.0;  ///< smallest distance of an active pair; NaN (null) with none
  int ccd_calls = 0;                  ///< max_step evaluations of the contact terms (CCD)
  int ccd_tests = 0;                  ///< primitive pairs (and plane points) those tested
  double contact_seconds = 0.0;       ///< wall time in the contact terms (energy, derivatives, stencil, CCD)
  std::vector<double> residuals;  ///< ‖g‖ at each Newton iteration of every substep
  std::string failure;
};

/// One field of a record.
struct RecordField {
  using Member = std::variant<int StepRecord::*, double StepRecord::*, bool StepRecord::*, std::string StepRecord::*,
                              std::vector<double> StepRecord::*>;
  const char* key;             ///< JSON key and CSV column
  Member member;
  const char* csv = nullptr;   ///< fmt format of its CSV column ({} for integers); nullptr: JSON only
  const char* label = nullptr; ///< the report's name for it (a plot series); nullptr: not plotted
  const char* plot = nullptr;  ///< the report plot it is drawn in
  bool total = false;          ///< summed over the records into a run-level field of the same key
};

/// A plot of the report: the fields naming it as their plot, against the table's x field.
struct RecordPlot {
  const char* id;
  const char* title;
  const char* y_label;
  bool log_y = false;
};

struct RecordTable {
  const char* records;   ///< the stats.json array: "steps" or "frames"
  const char* index;     ///< the index field's key: "step" or "frame"
  const char* x;         ///< the key plots use as x
  const char* group;     ///< the report's heading for the plots
  bool has_initial;      ///< a record for the initial state (frame 0)
  std::vector<RecordField> fields;
  std::vector<RecordPlot> plots;
};

/// The stretch test's steps (tetcli, hexcli, snh stretch).
[[nodiscard]] const RecordTable& stretch_table();
/// A scene's frames (snh run).
[[nodiscard]] const RecordTable& scene_table();
/// A flesh scene's frames (snh flesh, snh run with "flesh"): a scene's, with the render surface's volume
/// for the simulated flesh and for linear blend skinning.
[[nodiscard]] const RecordTable& flesh_table();
/// A scene's or flesh scene's table (`base`) with the contact fields (contact_pairs, min_contact_distance,
/// ccd_calls, ccd_tests, contact_seconds: the last three also as run totals) and their plots, for runs with
/// contact; runs without keep `base` (their files unchanged).
[[nodiscard]] const RecordTable& contact_table(const RecordTable& base);
/// The table whose `records` array is `name`; nullptr if none.
[[nodiscard]] const RecordTable* table_for(std::string_view records);

/// The record as a JSON object (non-finite numbers become null).
[[nodiscard]] nlohmann::json to_json(const RecordTable& table, const StepRecord& r);
/// A record read back from to_json's form; a missing or null number reads as NaN (0 for integers).
[[nodiscard]] StepRecord from_json(const RecordTable& table, const nlohmann::json& j);
/// The CSV header line and one record's line (without newline).
[[nodiscard]] std::string csv_header(const RecordTable& table);
[[nodiscard]] std::string csv_row(const RecordTable& table, const StepRecord& r);
/// stats.json's "schema": the records' name, index and x keys, every field's key (with its label and
/// plot where it has one) and the plots, for the report.
[[nodiscard]] nlohmann::json schema_json(const RecordTable& table);
/// Adds the run-level totals (fields marked `total`) of the records to `stats`.
void add_totals(const RecordTable& table, const std::vector<StepRecord>& records, nlohmann::json& stats);

}  // namespace snh
