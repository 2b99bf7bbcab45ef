#include "snh/report/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <functional>
#include <optional>
#include <limits>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/io/base64.hpp"
#include "snh/io/input_file.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/io/vtu.hpp"
#include "snh/report/fibres.hpp"
#include "snh/report/report_data.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/run/stats.hpp"

namespace snh {

report_internal::json report_internal::read_json(const std::filesystem::path& path) {
  if (const std::string problem = input_file_problem(path, "JSON file"); !problem.empty()) throw ReportError(problem);
  std::ifstream in(path);
  if (!in) throw ReportError(fmt::format("{}: cannot be opened", path.string()));
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw ReportError(fmt::format("{}: not valid JSON ({})", path.string(), e.what()));
  }
}

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace report_internal;

/// data.js is this, the JSON, then ";\n": a classic script the page loads from file://.
constexpr std::string_view kDataPrefix = "window.SNH_REPORT = ";

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// A value of stats.json as the page shows it.
std::string show(const json& v) {
  if (v.is_null()) return "–";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer()) return std::to_string(v.get<long long>());
  if (v.is_number()) return fmt::format("{:.6g}", v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  if (v.is_array()) {
    std::string s = "(";
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + show(v[i]);
    return s + ")";
  }
  return v.dump();
}

/// Adds [label, shown value] to `meta` when `key` is in `stats`.
void meta_from(json& meta, const json& stats, const char* key, const std::string& label, const std::string& unit = "") {
  if (const auto it = stats.find(key); it != stats.end()) meta.push_back({label, show(*it) + unit});
}

/// The values of `key` in each row (null where missing or not a number).
json column(const json& rows, const char* key) {
  json out = json::array();
  for (const json& r : rows) {
    const auto it = r.find(key);
    out.push_back(it != r.end() && it->is_number() ? *it : json(nullptr));
  }
  return out;
}

json plot(const std::string& id, const std::string& group, const std::string& title, const std::string& x_label,
          const std::string& y_label, bool log_y, const json& x, const json& series, bool points_only = false) {
  return {{"id", id}, {"group", group}, {"title", title}, {"x_label", x_label}, {"y_label", y_label}, {"log_y", log_y},
          {"points_only", points_only}, {"x", x}, {"series", series}};
}

json series(const std::string& label, const json& y) { return {{"label", label}, {"y", y}}; }

/// The report's view of a mesh: its boundary triangles over the surface's vertices and cells, numbered in
/// order of first use, with the rest positions and pinned flags of those vertices.
struct ReportSurface {
  Eigen::Index triangle_count = 0;
  std::vector<std::uint32_t> tri, tri_cell;  ///< 3 surface vertices and the surface cell per triangle
  std::vector<int> vertices, cells;          ///< the mesh's vertex and cell of each surface one
  std::vector<float> rest_xyz;
  std::vector<std::uint8_t> pinned;
  int pinned_count = 0;                      ///< over the whole mesh
};

ReportSurface report_surface(const VolumeMesh& rest, const VtuData& first) {
  const Eigen::Index nv = rest.vertex_count(), nc = rest.cell_count();
  std::vector<int> triangle_cell;
  const Eigen::Matrix3Xi triangles = boundary_triangles(rest, &triangle_cell);
  ReportSurface s;
  s.triangle_count = triangles.cols();
  // `local` maps a mesh index to its surface index, −1 until used; `used` lists the mesh indices in surface order.
  std::vector<int> vertex_local(nv, -1), cell_local(nc, -1);
  auto number = [](int index, std::vector<int>& local, std::vector<int>& used) {
    if (local[index] < 0) {
      local[index] = static_cast<int>(used.size());
      used.push_back(index);
    }
    return static_cast<std::uint32_t>(local[index]);
  };
  s.tri.resize(3 * triangles.cols());
  s.tri_cell.resize(triangles.cols());
  for (Eigen::Index t = 0; t < triangles.cols(); ++t) {
    for (int a = 0; a < 3; ++a) s.tri[3 * t + a] = number(triangles(a, t), vertex_local, s.vertices);
    s.tri_cell[t] = number(triangle_cell[t], cell_local, s.cells);
  }
  const std::size_t ns = s.vertices.size();
  s.rest_xyz.resize(3 * ns);
  s.pinned.assign(ns, 0);
  const auto pin_it = first.point_data.find("pinned");
  const bool has_pins = pin_it != first.point_data.end() && pin_it->second.size() == static_cast<std::size_t>(nv);
  if (has_pins)
    for (double p : pin_it->second) s.pinned_count += p != 0.0;
  for (std::size_t k = 0; k < ns; ++k) {
    for (int a = 0; a < 3; ++a) s.rest_xyz[3 * k + a] = static_cast<float>(rest.vertices(a, s.vertices[k]));
    if (has_pins) s.pinned[k] = pin_it->second[s.vertices[k]] != 0.0;
  }
  return s;
}

/// A field the view colours by, with its range over every frame.
struct Field {
  std::string name, label, per, colormap;
  Range range;
};

/// The cell fields written by FrameWriter (older runs may lack psi), then the displacement magnitude.
std::vector<Field> report_fields(const VtuData& first) {
  std::vector<Field> fields;
  if (first.cell_data.count("J")) fields.push_back({"J", "volume change J (smallest det F per element)", "cell", "diverging", {}});
  if (first.cell_data.count("psi")) fields.push_back({"psi", "energy density ψ (mean per element)", "cell", "sequential", {}});
  if (first.cell_data.count("contraction"))
    fields.push_back({"contraction", "muscle contraction α = γ × activation (per element)", "cell", "sequential", {}});
  fields.push_back({"displacement", "displacement |x − X|", "vertex", "sequential", {}});
  return fields;
}

/// One frame's surface positions and field values (the fields' ranges and the bounds grown by it).
json frame_values(const VtuData& data, const fs::path& file, const VolumeMesh& rest, const ReportSurface& surface,
                  std::vector<Field>& fields, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  const Eigen::Index nv = rest.vertex_count(), nc = rest.cell_count();
  const VolumeMesh& m = data.mesh.mesh;
  if (m.vertex_count() != nv || m.cell_count() != nc)
    throw ReportError(fmt::format("{}: {} points and {} cells, but frame 0 has {} and {}", file.string(), m.vertex_count(),
                                  m.cell_count(), nv, nc));
  json frame_json;
  const std::size_t ns = surface.vertices.size();
  std::vector<float> xyz(3 * ns);
  for (std::size_t k = 0; k < ns; ++k) {
    const Eigen::Vector3d p = m.vertices.col(surface.vertices[k]);
    for (int a = 0; a < 3; ++a) xyz[3 * k + a] = static_cast<float>(p[a]);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  frame_json["x"] = encode(xyz);
  for (Field& f : fields) {
    std::vector<float> values;
    if (f.per == "cell") {
      const auto it = data.cell_data.find(f.name);
      if (it == data.cell_data.end() || it->second.size() != static_cast<std::size_t>(nc))
        throw ReportError(fmt::format("{}: no cell field {} with {} values, as frame 0 has", file.string(), f.name, nc));
      for (double v : it->second) f.range.add(v);
      for (int c : surface.cells) values.push_back(static_cast<float>(it->second[c]));
    } else {
      const Eigen::VectorXd d = (m.vertices - rest.vertices).colwise().norm();
      for (Eigen::Index v = 0; v < nv; ++v) f.range.add(d[v]);
      for (int v : surface.vertices) values.push_back(static_cast<float>(d[v]));
    }
    frame_json[f.name] = encode(values);
  }
  return frame_json;
}

/// The 3D part of a run's report: reads the .vtu frames listed in frames.pvd, writes report/frames/NNN.js
/// (surface positions and fields of each frame, and a flesh run's render surface) and returns the "mesh"
/// object of data.js; `render` is set to the "render" object of a flesh run (surface/000.obj there), else null.
/// A frame in `unconverged` (a run that went past it) is labelled so.
json write_frames(const fs::path& dir, const std::string& frame_word, const std::vector<int>& unconverged, json& render,
                  json& distance_plot, double meters_per_unit) {
  std::vector<std::pair<double, std::string>> pvd;
  try {
    pvd = read_pvd(dir / "frames.pvd");
  } catch (const MeshError& e) {
    throw ReportError(e.what());
  }
  const fs::path frames_dir = dir / "report" / "frames";
  fs::create_directories(frames_dir);
  std::optional<RenderSurface> render_surface;
  if (fs::exists(dir / "surface" / "000.obj")) render_surface.emplace(dir, pvd.size(), 1000.0 * meters_per_unit);

  auto read_frame = [&](std::size_t i) {
    try {
      return read_vtu_data(dir / pvd[i].second);
    } catch (const MeshError& e) {
      throw ReportError(fmt::format("frame {}: {}", i, e.what()));
    }
  };
  VtuData first = read_frame(0);  // moved into the frame loop below: keep what is needed of it here
  VolumeMesh rest = first.mesh.mesh;
  const Eigen::Index nv = rest.vertex_count(), nc = rest.cell_count();
  if (nc == 0) throw ReportError(fmt::format("{}: no tet or hex cells", (dir / pvd[0].second).string()));
  // Rest positions: frame 0's points less its displacement (frame 0 may start deformed).
  if (const auto it = first.point_data.find("displacement"); it != first.point_data.end() && it->second.size() == static_cast<std::size_t>(3 * nv))
    rest.vertices -= Eigen::Map<const Eigen::Matrix3Xd>(it->second.data(), 3, nv);
  const ReportSurface surface = report_surface(rest, first);
  std::vector<Field> fields = report_fields(first);
  std::optional<ReportFibres> fibres;  // a run with muscles
  if (const fs::path m = dir / "muscles.json"; fs::exists(m)) fibres.emplace(read_json(m), m.string(), rest, pvd.size());

  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  json frames = json::array();
  for (std::size_t i = 0; i < pvd.size(); ++i) {
    const VtuData data = i == 0 ? std::move(first) : read_frame(i);
    json frame_json = frame_values(data, dir / pvd[i].second, rest, surface, fields, lo, hi);
    if (render_surface) frame_json["render"] = render_surface->frame(i, pvd[i].second);
    if (fibres && fibres->count() > 0) frame_json["fibres"] = fibres->frame(i, data.mesh.mesh.vertices, lo, hi);
    const std::string src = fmt::format("report/frames/{:03d}.js", i);
    write_atomically(dir / src, [&](std::ostream& o) { o << "snhReportFrame(" << i << ", " << frame_json.dump() << ");\n"; });
    const bool failed = std::find(unconverged.begin(), unconverged.end(), static_cast<int>(i)) != unconverged.end();
    frames.push_back({{"index", i}, {"time", pvd[i].first}, {"label", fmt::format("{} {}{}", frame_word, i, failed ? " (did not converge)" : "")},
                      {"src", src}});
  }
  // Frame files of an earlier, longer report of this directory would only confuse: remove them.
  for (std::size_t i = pvd.size();; ++i) {
    std::error_code ec;
    if (!fs::remove(frames_dir / fmt::format("{:03d}.js", i), ec)) break;
  }

  render = render_surface ? render_surface->summary() : json(nullptr);
  if (render_surface) {
    json times = json::array();
    for (const auto& f : pvd) times.push_back(f.first);
    // Beside the run's own "largest offset" (each vertex from its skinned position, sliding along the surface
    // included), the shape's difference: what the view's distance colouring shows.
    distance_plot = plot("lbs_surface_distance", "Flesh against skinning", "The flesh's largest distance from the skinned (LBS) surface",
                         "time", "mm", false, times,
                         json::array({series("largest distance outside", render_surface->outside()),
                                      series("largest distance inside", render_surface->inside())}));
  }
  json field_list = json::array();
  for (const Field& f : fields) {
    const json r = f.range.to_json(0.0);
    json entry = {{"name", f.name}, {"label", f.label}, {"per", f.per}, {"min", r[0]}, {"max", r[1]}, {"colormap", f.colormap}};
    if (f.colormap == "diverging") entry["center"] = 1.0;
    field_list.push_back(entry);
  }
  return {{"element", rest.type == CellType::tet4 ? "tet" : "hex"},
          {"vertex_count", nv},
          {"cell_count", nc},
          {"pinned_count", surface.pinned_count},
          {"surface",
           {{"vertex_count", surface.vertices.size()},
            {"cell_count", surface.cells.size()},
            {"triangle_count", surface.triangle_count},
            {"triangles", encode(surface.tri)},
            {"triangle_cells", encode(surface.tri_cell)},
            {"rest", encode(surface.rest_xyz)},
            {"pinned", encode(surface.pinned)}}},
          {"bounds", {{"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}}},
          {"fields", field_list},
          {"fibres", fibres && fibres->count() > 0 ? fibres->summary() : json(nullptr)},
          {"default_field", fields.front().name},
          {"frames", frames}};
}

/// A flesh run's own settings (stats.json of `snh flesh`, or of a scene with a "flesh" section): the flesh
/// volume, the vertices the bones bind, the bones, and a link to the USD stage when it is there.
void flesh_meta(json& meta, const fs::path& dir, const json& stats) {
  if (const auto it = stats.find("volume"); it != stats.end() && it->is_string()) {
    const std::string v = it->get<std::string>();
    meta.push_back({"flesh volume", v == "lattice" ? "hexahedral lattice (lattice)"
                                    : v == "tets"  ? "tetrahedra from TetGen (tets)"
                                                   : v});
  }
  meta_from(meta, stats, "bound_vertices", "bound vertices");
  if (const auto it = stats.find("bones"); it != stats.end() && it->is_array()) {
    std::string unbound;
    int count = 0;
    for (const json& b : *it) {
      ++count;
      if (b.is_object() && b.value("bound", 1) == 0)
        unbound += (unbound.empty() ? "" : ", ") + b.value("name", std::string("?"));
    }
    meta.push_back(
        {"bones", unbound.empty() ? std::to_string(count) : fmt::format("{} (binding no vertex: {})", count, unbound)});
  }
  if (const auto it = stats.find("radius_scale"); it != stats.end() && it->is_number() && it->get<double>() != 1.0)
    meta.push_back({"capsule radii", fmt::format("{:g} x the default", it->get<double>())});
  // Where the bones press their flesh inside out (the run's header warns of it too). A run that lists its warnings
  // (stats.json's "warnings") has it in the list under the status; only older runs show it here.
  if (const auto it = stats.find("pressed_flesh"); it != stats.end() && it->is_object() && !stats.contains("warnings")) {
    const json& p = *it;
    const json& bones = p.value("bones", json::array());
    meta.push_back({"warning: bones press flesh inside out",
                    fmt::format("in {} frame(s); worst frame {}: {} and {} carry bound vertices {:.3g} apart at rest to {:.3g} "
                                "(their capsules overlap; smaller radii leave the flesh room)",
                                p.value("frames", 0), p.value("worst_frame", 0), bones.size() > 0 ? bones[0].get<std::string>() : "?",
                                bones.size() > 1 ? bones[1].get<std::string>() : "?", p.value("rest_distance", 0.0),
                                p.value("closest", 0.0))});
  }
  const std::string usd =
      stats.contains("usd") && stats.at("usd").is_string() ? stats.at("usd").get<std::string>() : "flesh.usda";
  if (fs::exists(dir / usd)) meta.push_back({"USD stage", {{"text", usd}, {"href", usd}}});
}

/// The run's own verdict for the page's status: ok, its text, and what it warned of. rows: its frames or steps.
json run_status_of(const json& stats, const json& rows, bool scene) {
  const bool ok = stats.value("all_converged", false);
  const int signal = stats.value("interrupted_by_signal", 0);
  std::string status = ok ? (scene ? "finished" : "converged every step") : "";
  const std::string run_status = stats.value("status", std::string());
  if (run_status == "running")
    status = fmt::format("unfinished: stats.json was last written while the run was going, after {} {} (it was killed, "
                         "or is still running)",
                         scene ? "frame" : "step", rows.empty() ? 0 : rows.back().value(scene ? "frame" : "step", 0));
  else if (!ok && signal) status = fmt::format("interrupted by signal {} after {} {}", signal, scene ? "frame" : "step", rows.empty() ? 0 : rows.back().value(scene ? "frame" : "step", 0));
  else if (!ok && scene) {
    status = "stopped: " + stats.value("failure", std::string("a frame failed"));
    if (stats.contains("failed_frame") && stats.at("failed_frame").is_string())
      status += "; its last iterate, no result, is " + stats.at("failed_frame").get<std::string>();
  }
  else if (!ok) {
    status = "stopped: a step did not converge";
    if (!rows.empty()) status = fmt::format("stopped: step {} did not converge ({})", rows.back().value("step", 0), rows.back().value("failure", std::string()));
  }
  // What the run warned of (stats.json's "warnings"; runs before it have none): a finished run that did is
  // "finished with N warnings", and the page lists them under the status.
  json warnings = json::array();
  if (const auto it = stats.find("warnings"); it != stats.end() && it->is_array())
    for (const json& w : *it)
      if (w.is_string()) warnings.push_back(w);
  if (ok && run_status != "running" && !warnings.empty())
    status += fmt::format(" with {} warning{}", warnings.size(), warnings.size() == 1 ? "" : "s");
  return {{"ok", ok}, {"text", status}, {"warnings", warnings}};
}

/// The report data of a stretch run (tetcli, hexcli, snh stretch) or a scene (snh run).
json run_data(const fs::path& dir, const json& stats) {
  const bool scene = stats.contains("frames") && !stats.contains("steps");
  json d;
  d["format"] = 1;
  d["kind"] = scene ? "scene" : "stretch";
  const std::string program = stats.value("program", std::string(scene ? "snh run" : "snh stretch"));
  d["title"] = stats.contains("command_line") ? stats.at("command_line").get<std::string>()
               : scene                        ? "snh run " + stats.value("scene", std::string())
                                              : program;
  d["generated_by"] = "snh " SNH_VERSION;

  // Status: the run's own verdict.
  const auto rows_at = stats.find(scene ? "frames" : "steps");
  if (rows_at == stats.end() || !rows_at->is_array())
    throw ReportError(fmt::format("{}: no \"{}\" array", (dir / "stats.json").string(), scene ? "frames" : "steps"));
  const json& rows = *rows_at;
  d["status"] = run_status_of(stats, rows, scene);

  // Settings, in this order, each where stats.json has it.
  struct Setting {
    const char* key;
    const char* label;
    const char* unit = "";
  };
  static constexpr Setting kRun[] = {
      {"command_line", "command line"}, {"program", "program"}, {"scene", "scene file"}, {"model", "model"},
      {"animation", "animation"}, {"model_vertices", "model vertices"}, {"model_triangles", "model triangles"},
      {"joints", "joints"}, {"element", "element"}, {"resolution", "resolution"}, {"mesh_file", "mesh file"},
      {"vertices", "vertices"}, {"cells", "cells"}};
  static constexpr Setting kMaterial[] = {{"material", "material"}, {"mu", "μ"}, {"lambda", "λ"}};
  static constexpr Setting kSolverAndTotals[] = {
      {"density", "density"}, {"integrator", "integrator"}, {"dt", "dt"}, {"end_time", "end time"},
      {"gravity", "gravity"}, {"mass_damping", "mass damping"}, {"stiffness_damping", "stiffness damping"},
      {"steps_requested", "steps"}, {"stretch", "stretch", "×"}, {"axis", "axis"}, {"tet_split", "tet split"},
      {"solver", "linear solver"}, {"reuse_factor", "factor reuse"}, {"tolerance", "Newton tolerance"},
      {"newton_iterations", "Newton iterations"}, {"factorizations", "factorizations"},
      {"total_seconds", "total time", " s"}, {"peak_memory_mib", "peak memory", " MiB"},
      {"middle_width", "middle width"}, {"snh_version", "snh version"}};
  json meta = json::array();
  for (const Setting& m : kRun) meta_from(meta, stats, m.key, m.label, m.unit);
  flesh_meta(meta, dir, stats);
  for (const Setting& m : kMaterial) meta_from(meta, stats, m.key, m.label, m.unit);
  if (stats.contains("mu") && stats.contains("lambda") && stats.at("mu").is_number() && stats.at("lambda").is_number()) {
    const double mu = stats.at("mu").get<double>(), lambda = stats.at("lambda").get<double>();
    meta.push_back({"ν = λ / (2(λ + μ))", fmt::format("{:.6g}", lambda / (2.0 * (lambda + mu)))});
  }
  if (stats.contains("reparametrize"))
    meta.push_back({"parameters", stats.value("reparametrize", false) ? "linear (μ_L, λ_L), reparametrized (docs/math.md §2)"
                                                                      : "used as given"});
  for (const Setting& m : kSolverAndTotals) meta_from(meta, stats, m.key, m.label, m.unit);
  d["meta"] = meta;
  d["tables"] = json::array();

  // Plots, one point per step (stretch) or frame (scene), as the run's schema describes its columns (the
  // table the writer used, for a stats.json from before the schema was written).
  const json schema = stats.contains("schema") && stats.at("schema").is_object()
                          ? stats.at("schema")
                          : schema_json(*table_for(scene ? "frames" : "steps"));
  json plots = json::array();
  {
    const std::string x_key = schema.value("x", std::string(scene ? "time" : "step"));
    const json x = column(rows, x_key.c_str());
    const std::string group = schema.value("group", std::string());
    for (const json& p : schema.value("plots", json::array())) {
      json series_list = json::array();
      const std::string id = p.value("id", std::string());
      for (const json& c : schema.value("columns", json::array()))
        if (c.value("plot", std::string()) == id && c.contains("label"))
          series_list.push_back(series(c.value("label", std::string()), column(rows, c.value("key", std::string()).c_str())));
      plots.push_back(plot(id, group, p.value("title", std::string()), x_key, p.value("y_label", std::string()),
                           p.value("log_y", false), x, series_list));
    }
  }
  d["plots"] = plots;

  d["mesh"] = nullptr;
  d["render"] = nullptr;
  if (fs::exists(dir / "frames.pvd")) {
    std::vector<int> unconverged;
    if (const auto it = stats.find("unconverged_frames"); it != stats.end() && it->is_array())
      for (const json& f : *it)
        if (f.is_number_integer()) unconverged.push_back(f.get<int>());
    json distance_plot;
    const auto mpu = stats.find("model_meters_per_unit");
    const double meters_per_unit = mpu != stats.end() && mpu->is_number() && mpu->get<double>() > 0.0 ? mpu->get<double>() : 1.0;
    d["mesh"] = write_frames(dir, scene ? "frame" : "step", unconverged, d["render"], distance_plot, meters_per_unit);
    if (d["render"].is_object())  // the model's up axis, which the views' names depend on
      d["render"]["up_axis"] = stats.contains("model_up_axis") && stats.at("model_up_axis").is_string() ? stats.at("model_up_axis") : json("+Y");
    if (!distance_plot.is_null()) {
      if (!d["plots"].empty()) distance_plot["group"] = d["plots"].front().value("group", std::string());  // beside the run's own
      d["plots"].push_back(distance_plot);
    }
  }
  else d["meta"].push_back({"3D view", "none: the run wrote no .vtu frames (frames.pvd is missing)"});
  return d;
}

struct Curves {
  std::vector<double> x;
  json series = json::array();
};

/// Curves of one value of a lab table's rows against another: x is the sorted distinct values of `x_key`
/// over every row; a row that `label` names adds its `y_key` at its x to the series of that name (series
/// in order of first appearance; null where a series has no row at an x).
Curves curves(const json& rows, const char* x_key, const char* y_key,
              const std::function<std::optional<std::string>(const json&)>& label) {
  Curves c;
  for (const json& r : rows)
    if (const double v = r.value(x_key, 0.0); std::find(c.x.begin(), c.x.end(), v) == c.x.end()) c.x.push_back(v);
  std::sort(c.x.begin(), c.x.end());
  std::vector<std::string> names;
  for (const json& r : rows) {
    const std::optional<std::string> name = label(r);
    if (!name) continue;
    auto it = std::find(names.begin(), names.end(), *name);
    if (it == names.end()) {
      names.push_back(*name);
      c.series.push_back(series(*name, json(std::vector<std::nullptr_t>(c.x.size(), nullptr))));
      it = names.end() - 1;
    }
    const auto at = std::find(c.x.begin(), c.x.end(), r.value(x_key, 0.0)) - c.x.begin();
    c.series[it - names.begin()]["y"][at] = r.value(y_key, json(nullptr));
  }
  return c;
}

/// The report data of a lab (lab.json): its tables, curves and a table of every simulation, each of
/// whose own report is written on the way (`runs` counts them).
json lab_data(const fs::path& dir, const json& lab, const std::string& bundle_src, int& runs) {
  json d;
  d["format"] = 1;
  d["kind"] = "lab";
  d["title"] = lab.value("command_line", std::string("snh lab"));
  d["generated_by"] = "snh " SNH_VERSION;
  d["status"] = {{"ok", true}, {"text", "every experiment ran"}};
  json meta = json::array();
  meta_from(meta, lab, "command_line", "command line");
  meta_from(meta, lab, "quick", "quick");
  meta_from(meta, lab, "energies", "energies");
  meta_from(meta, lab, "trap_size", "trap size (production SNH, μ 1, λ 10)");
  meta_from(meta, lab, "total_seconds", "total time", " s");
  meta_from(meta, lab, "snh_version", "snh version");
  d["meta"] = meta;
  json tables = lab.value("tables", json::array());

  // Every simulation, with a link to its own report.
  json run_rows = json::array();
  runs = 0;
  auto add_run = [&](const json& r, const std::string& what, const std::string& outcome) {
    const std::string sub = r.value("dir", std::string());
    json link = nullptr;
    if (!sub.empty() && fs::exists(dir / sub / "stats.json")) {
      std::string up;
      for (const auto& part : fs::path(sub)) up += part.empty() ? "" : "../";
      try {  // one simulation's broken output costs its own page only
        (void)write_report(dir / sub, {.bundle_src = up + bundle_src, .write_bundle = false});
        ++runs;
        link = {{"text", "report"}, {"href", sub + "/index.html"}};
      } catch (const std::exception& e) {
        link = std::string("no report: ") + e.what();
      }
    }
    run_rows.push_back({what, r.value("energy", std::string()), outcome, link});
  };
  json plots = json::array();
  for (const char* experiment : {"rest", "inversion", "reflection", "degeneracy"}) {
    if (!lab.contains(experiment)) continue;
    const json& list = lab.at(experiment);
    // One plot per case: the volume ratio over time, a series per energy.
    std::vector<std::string> cases;
    for (const json& r : list) {
      const std::string c = r.value("case", std::string());
      if (std::find(cases.begin(), cases.end(), c) == cases.end()) cases.push_back(c);
    }
    for (const std::string& c : cases) {
      json x = json::array(), ser = json::array();
      for (const json& r : list)
        if (r.value("case", std::string()) == c && r.contains("time") && r.at("time").size() > x.size()) x = r.at("time");
      for (const json& r : list) {
        if (r.value("case", std::string()) != c) continue;
        json y = r.value("volume", json::array());
        while (y.size() < x.size()) y.push_back(nullptr);
        ser.push_back(series(r.value("energy", std::string()), y));
        add_run(r, std::string(experiment) + " / " + c,
                !r.value("defined_at_start", true) ? "undefined at the start"
                : !r.value("converged", true)      ? "Newton failed"
                                                   : fmt::format("volume {}{}", show(r.value("final_volume", json(nullptr))),
                                                                 r.value("recovered", false) ? ", recovered" : ""));
      }
      plots.push_back(plot(fmt::format("{}_{}", experiment, c), "Volume over time", fmt::format("{}: {}", experiment, c),
                           "time", "volume ratio", false, x, ser));
    }
  }
  // Poisson's ratio: measured against expected, a series per energy and parametrization.
  if (lab.contains("poisson")) {
    for (const json& r : lab.at("poisson"))
      if (r.value("ran", false))
        add_run(r,
                fmt::format("poisson / nu {} {}", show(r.value("nu", json(nullptr))),
                            r.value("reparametrize", false) ? "reparametrized" : "given"),
                fmt::format("measured ν {}", show(r.value("measured", json(nullptr)))));
    const Curves c = curves(lab.at("poisson"), "expected", "measured", [](const json& r) -> std::optional<std::string> {
      if (!r.value("ran", false)) return std::nullopt;
      return r.value("energy", std::string()) + (r.value("reparametrize", false) ? " (reparametrized)" : " (given)");
    });
    json ser = json::array({series("expected", json(c.x))});
    ser.insert(ser.end(), c.series.begin(), c.series.end());
    plots.push_back(plot("poisson", "Poisson's ratio", "Measured against expected ν", "expected ν", "measured ν", false,
                         json(c.x), ser, true));
  }
  // Large stretch: volume ratio at 3.5× against ν.
  if (lab.contains("stretch")) {
    for (const json& r : lab.at("stretch"))
      add_run(r, fmt::format("stretch / nu {}", show(r.value("nu", json(nullptr)))),
              fmt::format("volume {}", show(r.value("volume_ratio", json(nullptr)))));
    const Curves c = curves(lab.at("stretch"), "nu", "volume_ratio",
                            [](const json& r) -> std::optional<std::string> { return r.value("energy", std::string()); });
    plots.push_back(plot("stretch", "Large stretch", "Volume ratio at 3.5× stretch", "ν", "volume ratio", false, json(c.x), c.series));
  }
  // ψ along F = sI.
  if (lab.contains("psi_along_sI")) {
    const json& p = lab.at("psi_along_sI");
    json ser = json::array();
    const json psi = p.value("psi", json::object());
    for (const auto& [energy, values] : psi.items()) ser.push_back(series(energy, values));
    json psi_plot = plot("psi_sI", "Energy along F = sI",
                         fmt::format("ψ(sI), μ {}, λ {} (gaps: undefined; clipped at 60)", show(p.value("mu", json(nullptr))),
                                     show(p.value("lambda", json(nullptr)))),
                         "s", "ψ", false, p.value("s", json::array()), ser);
    psi_plot["y_range"] = {-5.0, 60.0};  // the log J energies reach ~1e3 near s = 0, which would flatten the rest
    plots.push_back(psi_plot);
  }
  tables.push_back({{"title", "Every simulation"},
                    {"note", "each with its own report: 3D playback of its frames and its per-frame plots"},
                    {"columns", {"experiment", "energy", "outcome", "report"}},
                    {"rows", run_rows}});
  d["tables"] = tables;
  d["plots"] = plots;
  d["mesh"] = nullptr;
  return d;
}

/// Refuses a path that is not a directory, saying what it is instead: missing, unreadable, or a file.
void check_run_directory(const fs::path& dir) {
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (!fs::exists(st)) {
    if (ec && ec != std::errc::no_such_file_or_directory) throw ReportError(fmt::format("{}: {}", dir.string(), ec.message()));
    throw ReportError(fmt::format("{}: does not exist", dir.string()));
  }
  if (!fs::is_directory(st)) throw ReportError(fmt::format("{}: is not a directory (the output directory of a run is expected)", dir.string()));
}

}  // namespace

json read_report_data(const fs::path& dir) {
  const fs::path path = dir / "report" / "data.js";
  std::error_code ec;
  if (fs::exists(fs::symlink_status(path, ec)))
    if (const std::string problem = input_file_problem(path, "report data file"); !problem.empty()) throw ReportError(problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ReportError(fmt::format("{}: cannot be opened: run snh report {}", path.string(), dir.string()));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  try {
    if (text.compare(0, kDataPrefix.size(), kDataPrefix) != 0) throw std::runtime_error("no window.SNH_REPORT");
    while (!text.empty() && (text.back() == '\n' || text.back() == ';')) text.pop_back();
    return json::parse(text.substr(kDataPrefix.size()));
  } catch (const std::exception& e) {
    throw ReportError(fmt::format("{}: not a report's data ({}): run snh report {} again", path.string(), e.what(),
                                  dir.string()));
  }
}

ReportSummary write_report(const fs::path& dir, const ReportOptions& options) {
  check_run_directory(dir);
  ReportSummary summary;
  json data;
  const bool lab = fs::exists(dir / "lab.json");
  const fs::path source = dir / (lab ? "lab.json" : "stats.json");
  try {
    if (!lab && !fs::exists(source))
      throw ReportError(fmt::format("{}: no stats.json or lab.json here: not the output directory of an snh run", dir.string()));
    const json in = read_json(source);
    if (!in.is_object()) throw ReportError(fmt::format("{}: not a JSON object", source.string()));
    fs::create_directories(dir / "report");
    try {
      data = lab ? lab_data(dir, in, options.bundle_src, summary.runs) : run_data(dir, in);
    } catch (const json::exception& e) {  // a key of an unexpected type
      throw ReportError(fmt::format("{}: unexpected content ({})", source.string(), e.what()));
    }
    fs::create_directories(dir / "report");
    summary.kind = data["kind"].get<std::string>();
    if (!data["mesh"].is_null()) summary.frames = static_cast<int>(data["mesh"]["frames"].size());
    write_atomically(dir / "report" / "data.js", [&](std::ostream& o) {
      o << kDataPrefix << data.dump(-1, ' ', false, json::error_handler_t::replace) << ";\n";
    });
    if (options.write_bundle) {
      const std::string_view bundle = report_bundle();
      write_atomically(dir / "report" / "snh-report.js",
                       [&](std::ostream& o) { o.write(bundle.data(), static_cast<std::streamsize>(bundle.size())); });
    }
  } catch (const fs::filesystem_error& e) {  // the report/ directory cannot be made
    throw WriteError(fmt::format("{}: {}", dir.string(), e.what()));
  }
  summary.index = dir / "index.html";
  const std::string title = html_escape(data["title"].get<std::string>());
  write_atomically(summary.index, [&](std::ostream& o) {
    o << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>snh report: "
      << title << "</title></head>\n<body><div id=\"snh-report\"></div>\n<noscript>This report needs JavaScript.</noscript>\n"
      << "<script src=\"report/data.js\"></script>\n<script src=\"" << html_escape(options.bundle_src)
      << "\"></script>\n</body></html>\n";
  });
  return summary;
}

}  // namespace snh
