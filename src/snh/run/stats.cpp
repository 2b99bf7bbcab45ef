#include "snh/run/stats.hpp"

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace snh {
namespace {

using json = nlohmann::json;
using R = StepRecord;

// The fields shared by both tables, as the stretch test has written them since issue 3.
RecordField newton() { return {"newton_iterations", &R::newton_iterations, "{}", "Newton iterations", "newton", true}; }
RecordField halvings() { return {"line_search_steps", &R::line_search_steps, "{}", "line-search halvings", "newton"}; }
RecordField cg() { return {"linear_iterations", &R::linear_iterations, "{}", nullptr, nullptr, true}; }
RecordField factorizations() { return {"factorizations", &R::factorizations, "{}", nullptr, nullptr, true}; }
RecordField volume() { return {"volume_ratio", &R::volume_ratio, "{:.9g}", "volume ratio", "volume"}; }
RecordField min_J() { return {"min_J", &R::min_J, "{:.9g}", "min J", "min_J"}; }
RecordField inverted() { return {"inverted", &R::inverted, "{}"}; }
RecordField converged() { return {"converged", &R::converged, "{}"}; }
RecordField failure() { return {"failure", &R::failure}; }

}  // namespace

const RecordTable& stretch_table() {
  static const RecordTable table{
      .records = "steps",
      .index = "step",
      .x = "step",
      .group = "Per step",
      .has_initial = false,
      .fields = {{"step", &R::index, "{}"},
                 converged(),
                 newton(),
                 halvings(),
                 cg(),
                 factorizations(),
                 {"true_hessian_steps", &R::true_hessian_steps, nullptr, nullptr, nullptr, true},
                 {"residual", &R::residual, "{:.6e}", "residual", "residual"},
                 {"energy", &R::energy, "{:.12g}", "energy", "energy"},
                 {"wall_seconds", &R::wall_seconds, "{:.6f}", "wall", "wall"},
                 {"assembly_seconds", &R::assembly_seconds, "{:.6f}", "assembly", "wall", true},
                 {"solve_seconds", &R::solve_seconds, "{:.6f}", "linear solve", "wall", true},
                 min_J(),
                 inverted(),
                 volume(),
                 {"residual_history", &R::residuals},
                 failure()},
      .plots = {{"newton", "Newton iterations", "iterations"},
                {"residual", "Residual ‖f‖", "‖f‖", true},
                {"energy", "Elastic energy", "energy"},
                {"volume", "Volume ratio (deformed / rest)", "ratio"},
                {"min_J", "Smallest det F", "min J"},
                {"wall", "Wall time", "seconds"}}};
  return table;
}

const RecordTable& scene_table() {
  static const RecordTable table{
      .records = "frames",
      .index = "frame",
      .x = "time",
      .group = "Per frame",
      .has_initial = true,
      .fields = {{"frame", &R::index, "{}"},
                 {"time", &R::time, "{:.9g}"},
                 {"substeps", &R::substeps, "{}"},
                 converged(),
                 {"newton_iterations", &R::newton_iterations, "{}", "Newton iterations", "newton"},
                 halvings(),
                 {"linear_iterations", &R::linear_iterations, "{}"},
                 {"factorizations", &R::factorizations, "{}"},
                 {"residual", &R::residual, "{:.6e}", "residual", "residual"},
                 {"newton_step", &R::newton_step, "{:.6e}"},
                 {"elastic_energy", &R::elastic_energy, "{:.12g}", "elastic", "energy"},
                 {"kinetic_energy", &R::kinetic_energy, "{:.12g}", "kinetic", "energy"},
                 {"gravity_energy", &R::gravity_energy, "{:.12g}", "gravity", "energy"},
                 {"total_energy", &R::total_energy, "{:.12g}", "total", "energy"},
                 volume(),
                 min_J(),
                 inverted(),
                 {"wall_seconds", &R::wall_seconds, "{:.6f}", "wall", "wall"},
                 {"assembly_seconds", &R::assembly_seconds, "{:.6f}", "assembly", "wall", true},
                 {"solve_seconds", &R::solve_seconds, "{:.6f}", "linear solve", "wall", true},
                 failure()},
      .plots = {{"newton", "Newton iterations", "iterations"},
                {"residual", "Residual ‖g‖ (largest of the substeps)", "‖g‖", true},
                {"energy", "Energy", "energy"},
                {"volume", "Volume ratio (deformed / rest)", "ratio"},
                {"min_J", "Smallest det F", "min J"},
                {"wall", "Wall time", "seconds"}}};
  return table;
}

const RecordTable& flesh_table() {
  static const RecordTable table = [] {
    RecordTable t = scene_table();
    t.fields.insert(t.fields.end() - 1, {{"surface_volume_ratio", &R::surface_volume_ratio, "{:.9g}", "flesh", "render_volume"},
                                         {"lbs_volume_ratio", &R::lbs_volume_ratio, "{:.9g}", "linear blend skinning",
                                          "render_volume"},
                                         {"lbs_distance", &R::lbs_distance, "{:.9g}", "largest", "lbs_distance"},
                                         {"tip_distance", &R::tip_distance, "{:.9g}", "at the skeleton's ends (fingertips, toes)",
                                          "lbs_distance"}});
    t.plots.push_back({"render_volume", "Volume inside the render surface (posed / rest)", "ratio"});
    t.plots.push_back({"lbs_distance", "Flesh against skinning: the render surface's largest offset", "model units"});
    return t;
  }();
  return table;
}

namespace {

RecordTable with_contact(RecordTable t) {
  t.fields.insert(t.fields.end() - 1,
                  {{"contact_pairs", &R::contact_pairs, "{}", "active pairs", "contact"},
                   {"min_contact_distance", &R::min_contact_distance, "{:.6e}", "smallest distance", "contact_distance"},
                   {"ccd_calls", &R::ccd_calls, "{}", nullptr, nullptr, true},
                   {"ccd_tests", &R::ccd_tests, "{}", nullptr, nullptr, true},
                   {"contact_seconds", &R::contact_seconds, "{:.6f}", "contact terms", "wall", true}});
  t.plots.push_back({"contact", "Active contact pairs", "pairs"});
  t.plots.push_back({"contact_distance", "Smallest contact distance", "distance", true});
  return t;
}

}  // namespace

const RecordTable& contact_table(const RecordTable& base) {
  static const RecordTable scene = with_contact(scene_table()), flesh = with_contact(flesh_table());
  if (&base == &flesh_table() || &base == &flesh) return flesh;
  return scene;
}

const RecordTable* table_for(std::string_view records) {
  for (const RecordTable* t : {&stretch_table(), &scene_table()})
    if (records == t->records) return t;
  return nullptr;
}

json to_json(const RecordTable& table, const StepRecord& r) {
  json j = json::object();
  for (const RecordField& f : table.fields)
    std::visit(
        [&](auto m) {
          using T = std::decay_t<decltype(r.*m)>;
          if constexpr (std::is_same_v<T, double>) {
            if (std::isfinite(r.*m)) j[f.key] = r.*m;
            else j[f.key] = nullptr;
          } else {
            j[f.key] = r.*m;
          }
        },
        f.member);
  return j;
}

StepRecord from_json(const RecordTable& table, const json& j) {
  StepRecord r;
  for (const RecordField& f : table.fields) {
    const auto it = j.find(f.key);
    const bool present = it != j.end() && !it->is_null();
    std::visit(
        [&](auto m) {
          using T = std::decay_t<decltype(r.*m)>;
          if constexpr (std::is_same_v<T, double>) {
            r.*m = present && it->is_number() ? it->template get<double>() : std::numeric_limits<double>::quiet_NaN();
          } else if constexpr (std::is_same_v<T, int>) {
            r.*m = present && it->is_number_integer() ? it->template get<int>() : 0;
          } else if constexpr (std::is_same_v<T, bool>) {
            r.*m = present && it->is_boolean() && it->template get<bool>();
          } else if constexpr (std::is_same_v<T, std::string>) {
            r.*m = present && it->is_string() ? it->template get<std::string>() : std::string();
          } else {
            (r.*m).clear();
            if (present && it->is_array())
              for (const json& v : *it) (r.*m).push_back(v.is_number() ? v.get<double>() : std::numeric_limits<double>::quiet_NaN());
          }
        },
        f.member);
  }
  return r;
}

std::string csv_header(const RecordTable& table) {
  std::string out;
  for (const RecordField& f : table.fields) {
    if (!f.csv) continue;
    if (!out.empty()) out += ',';
    out += f.key;
  }
  return out;
}

std::string csv_row(const RecordTable& table, const StepRecord& r) {
  std::string out;
  bool first = true;
  for (const RecordField& f : table.fields) {
    if (!f.csv) continue;
    if (!first) out += ',';
    first = false;
    std::visit(
        [&](auto m) {
          using T = std::decay_t<decltype(r.*m)>;
          if constexpr (std::is_same_v<T, bool>) out += r.*m ? "1" : "0";
          else if constexpr (std::is_same_v<T, double>) {
            // A value that does not exist (no contact pair in range: NaN) is an empty field, as JSON writes null;
            // no nan or inf reaches the file.
            if (std::isfinite(r.*m)) out += fmt::format(fmt::runtime(f.csv), r.*m);
          } else if constexpr (std::is_same_v<T, int>) {
            out += fmt::format(fmt::runtime(f.csv), r.*m);
          }
        },
        f.member);
  }
  return out;
}

json schema_json(const RecordTable& table) {
  json columns = json::array(), plots = json::array();
  for (const RecordField& f : table.fields) {
    json c = {{"key", f.key}};
    if (f.label) c["label"] = f.label;
    if (f.plot) c["plot"] = f.plot;
    columns.push_back(c);
  }
  for (const RecordPlot& p : table.plots)
    plots.push_back({{"id", p.id}, {"title", p.title}, {"y_label", p.y_label}, {"log_y", p.log_y}});
  return {{"records", table.records}, {"index", table.index}, {"x", table.x}, {"group", table.group},
          {"columns", columns}, {"plots", plots}};
}

void add_totals(const RecordTable& table, const std::vector<StepRecord>& records, json& stats) {
  for (const RecordField& f : table.fields) {
    if (!f.total) continue;
    std::visit(
        [&](auto m) {
          using T = std::decay_t<decltype(StepRecord{}.*m)>;
          if constexpr (std::is_same_v<T, int> || std::is_same_v<T, double>) {
            T sum = 0;
            for (const StepRecord& r : records) sum += r.*m;
            stats[f.key] = sum;
          }
        },
        f.member);
  }
}

}  // namespace snh
