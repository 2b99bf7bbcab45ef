#include "snh/setup/flesh_scene.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <numbers>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/io/obj.hpp"
#include "snh/io/pc2.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/io/usda.hpp"
#include "snh/run/output.hpp"
#include "snh/run/stats.hpp"

namespace snh {
namespace {

using json = nlohmann::json;

std::string frame_name(int index) { return fmt::format("{:03d}.obj", index); }

/// The flesh's settings in stats.json: the model, the volume, the binding.
void add_flesh_settings(const Flesh& flesh, const FleshSpec& spec, json& settings) {
  const RiggedModel& m = flesh.model;
  json bones = json::array();
  for (std::size_t b = 0; b < flesh.bones.size(); ++b)
    bones.push_back({{"name", flesh.bones[b].name}, {"radius", flesh.bones[b].radius}, {"bound", flesh.bound_per_bone[b]}});
  settings["model"] = spec.model.string();
  settings["volume"] = spec.volume == FleshVolume::lattice ? "lattice" : "tets";
  settings["resolution"] = flesh.resolution;
  settings["resolution_reason"] = flesh.resolution_reason;
  settings["cell_size"] = flesh.cell_size;
  settings["animation"] = flesh.clip.name;
  settings["model_vertices"] = m.vertices.cols();
  settings["model_triangles"] = m.triangles.cols();
  settings["joints"] = m.skeleton.size();
  settings["bound_vertices"] = flesh.binding.vertex.size();
  settings["free_parts"] = flesh.free_parts;
  settings["volume_of_cells"] = flesh.volume_of_cells;
  settings["split_cells"] = spec.split_cells;
  settings["split_cubes"] = flesh.split_cubes;
  settings["copied_vertices"] = flesh.copied_vertices;
  settings["join_meshes"] = spec.join_meshes;
  settings["solids"] = flesh.solids;
  settings["seam_vertices"] = flesh.seam_vertices;
  settings["surface_volume"] = flesh.surface_volume;
  settings["bones"] = bones;
  settings["radius_scale"] = spec.radius_scale;
  settings["joint_cells"] = to_string(spec.joint_cells);
  settings["released_vertices"] = flesh.released.vertex.size();
  json parts = json::array();
  for (const ModelPart& p : m.parts) parts.push_back({{"name", p.name}, {"first_vertex", p.first_vertex}, {"vertices", p.vertices}});
  settings["parts"] = parts;
  settings["skipped_meshes"] = m.skipped;
  settings["model_format"] = m.format;
  settings["model_notes"] = m.notes;
  settings["model_meters_per_unit"] = m.meters_per_unit;
  settings["model_up_axis"] = std::string(m.up_sign < 0 ? "-" : "+") + "XYZ"[m.up_axis];
  settings["open_edges"] = flesh.edges.open;
  settings["non_manifold_edges"] = flesh.edges.non_manifold;
  settings["inside_out"] = flesh.inside_out;
  const BindPose& bind = flesh.bind;
  settings["bind_pose"] = {{"placed", bind.placed}, {"placement_scale", bind.placement.scale},
                           {"placement_degrees", bind.placement.angle() * 180.0 / std::numbers::pi},
                           {"rest_is_bind", bind.rest_is_bind}, {"worst_joint", bind.worst_joint}, {"worst_offset", bind.worst_offset}};
  if (spec.soft_shell > 0.0)
    settings["soft_binding"] = {{"shell", spec.soft_shell}, {"stiffness", spec.soft_stiffness}, {"vertices", flesh.soft.vertex.size()}};
}

/// One line on a skin that is more than one closed, outward mesh: its parts, holes, orientation, and the
/// meshes not read; empty for one closed, outward mesh.
std::string describe_skin(const Flesh& flesh) {
  const RiggedModel& m = flesh.model;
  std::string out;
  if (m.parts.size() > 1) {
    std::string names;
    for (std::size_t i = 0; i < m.parts.size(); ++i) names += fmt::format("{}{} ({})", i ? ", " : "", m.parts[i].name, m.parts[i].vertices);
    out = fmt::format("skin: {} skinned meshes, {}", m.parts.size(), names);
  }
  const auto add = [&out](const std::string& s) { out += (out.empty() ? "skin: " : "; ") + s; };
  if (flesh.edges.open > 0 || flesh.edges.non_manifold > 0)
    add(fmt::format("{} open and {} non-manifold edges (holes and overlaps: inside is where the generalized winding number "
                    "says, |w| > 1/2)",
                    flesh.edges.open, flesh.edges.non_manifold));
  if (flesh.inside_out) add("its triangles face inwards (taken as they are: the inside test takes either orientation)");
  if (!m.skipped.empty()) {
    std::string names;
    for (std::size_t i = 0; i < m.skipped.size(); ++i) names += (i ? ", " : "") + m.skipped[i];
    add(fmt::format("not read, bound to another skin: {}", names));
  }
  return out;
}

/// The header's lines on the model, the volume and the binding.
void write_flesh_header(const Flesh& flesh, const FleshSpec& spec, std::ostream& o) {
  const RiggedModel& m = flesh.model;
  o << fmt::format("model {} ({}): {} vertices ({} welded), {} triangles, {} joints (hierarchy from the {}), animation \"{}\" "
                   "of {:g} s\n",
                   m.source.string(), m.format, m.vertices.cols(), m.surface_vertices.cols(), m.triangles.cols(), m.skeleton.size(),
                   m.hierarchy == "names" ? "joint names" : "file", flesh.clip.name, flesh.clip.duration());
  for (const std::string& note : m.notes) o << "model: " << note << "\n";
  if (const std::string skin = describe_skin(flesh); !skin.empty()) o << skin << "\n";
  o << fmt::format("volume: {} at resolution {} ({}; {} {:.4g} wide): {} cells, {} vertices; volume {:.6g} against the "
                   "surface's {:.6g} ({:.3f}x)\n",
                   spec.volume == FleshVolume::lattice ? "hexahedral lattice" : "tets (TetGen)", flesh.resolution, flesh.resolution_reason,
                   spec.volume == FleshVolume::lattice ? "cubes" : "tets no larger than a sixth of a cube", flesh.cell_size,
                   flesh.volume.cell_count(), flesh.volume.vertex_count(), flesh.volume_of_cells, flesh.surface_volume,
                   flesh.volume_of_cells / flesh.surface_volume);
  if (flesh.copied_vertices > 0)
    o << fmt::format("volume: the skin separates material closer than a cube ({} cubes split into a cell per piece); {} vertices "
                     "at shared grid nodes keep the parts apart, so they are not glued together\n",
                     flesh.split_cubes, flesh.copied_vertices);
  if (flesh.solids.size() > 1) {
    std::string names;
    for (std::size_t i = 0; i < flesh.solids.size(); ++i) names += (i ? "; " : "") + flesh.solids[i];
    o << fmt::format("volume: {} solids, kept apart where they overlap and each held by its own joints' bones (their skins share "
                     "no joint; --join-meshes makes one), glued at {} skin vertices they share: {}\n",
                     flesh.solids.size(), flesh.seam_vertices, names);
  }
  if (const std::string bind = describe(flesh.bind); !bind.empty()) o << bind << "\n";
  std::string counts;
  for (std::size_t b = 0; b < flesh.bones.size(); ++b)
    counts += fmt::format("{}{} {}", b ? ", " : "", flesh.bones[b].name, flesh.bound_per_bone[b]);
  o << fmt::format("bones: {} binding {} volume vertices{} ({})\n", flesh.bones.size(), flesh.binding.vertex.size(),
                   spec.radius_scale != 1.0 ? fmt::format(", capsule radii {:g} x the default", spec.radius_scale) : "", counts);
  if (!flesh.free_parts.empty()) {
    std::string parts;
    for (std::size_t i = 0; i < flesh.free_parts.size(); ++i) parts += (i ? ", " : "") + flesh.free_parts[i];
    o << fmt::format("bones: {} parts of the volume hold no bone's capsule and follow the joint their skin is weighted to, whole ({})\n",
                     flesh.free_parts.size(), parts);
  }
  if (!flesh.released.vertex.empty())
    o << fmt::format("joints: {} vertices of capsules in cells spanning two joints {} (joint cells {})\n", flesh.released.vertex.size(),
                     spec.joint_cells == JointCells::soft ? "bound softly instead" : "released", to_string(spec.joint_cells));
  if (spec.soft_shell > 0.0)
    o << fmt::format("soft binding: {} more volume vertices within {:.4g} of the capsules, pulled by springs of {:g} x E x h "
                     "(fading to 0 at the shell's edge)\n",
                     flesh.soft.vertex.size(), spec.soft_shell, spec.soft_stiffness);
}

/// The flesh's warnings (RunPlan::warnings): bones that bind no volume vertex, and where the bones press their
/// flesh inside out.
std::vector<std::string> flesh_warnings(const Flesh& flesh, const PressedFlesh& pressed) {
  std::vector<std::string> w;
  for (std::size_t b = 0; b < flesh.bones.size(); ++b)
    if (flesh.bound_per_bone[b] == 0)
      w.push_back(fmt::format("bone {} binds no volume vertex (capsule radius {:.4g}; cells {:.4g} wide)", flesh.bones[b].name,
                              flesh.bones[b].radius, flesh.cell_size));
  if (pressed.frame >= 0)
    w.push_back(fmt::format("the bones press flesh inside out in {} frame{}: in frame {} (t = {:.4g}) {} and {} carry bound "
                            "vertices {:.3g} apart at rest to {:.3g} ({:.0f} %), where their capsules overlap; the flesh between "
                            "cannot keep its volume (a smaller --radius-scale, or smaller radii for these bones, leaves it room)",
                            pressed.frames, pressed.frames == 1 ? "" : "s", pressed.frame + 1, pressed.time,
                            flesh.bones[pressed.bone_a].name, flesh.bones[pressed.bone_b].name, pressed.rest, pressed.closest,
                            100.0 * pressed.closest / pressed.rest));
  return w;
}

/// The file name of part p's flesh cache: flesh_NAME.pc2, the name kept to letters, digits, '-' and '_' (others
/// become '_'), and the part's index added when two parts would share a name.
std::string part_cache_name(const std::vector<ModelPart>& parts, std::size_t p) {
  const auto clean = [](const std::string& name) {
    std::string s;
    for (const char c : name) s += (std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_') ? c : '_';
    return s.empty() ? std::string("mesh") : s;
  };
  const std::string mine = clean(parts[p].name);
  bool shared = false;
  for (std::size_t q = 0; q < parts.size(); ++q) shared = shared || (q != p && clean(parts[q].name) == mine);
  return shared ? fmt::format("flesh_{}_{}.pc2", mine, p) : fmt::format("flesh_{}.pc2", mine);
}

/// flesh.usda from the surface/ and lbs/ frames on disk (so that a resumed run's stage holds them all), and
/// bones.json (the bones' segments at every frame written, for the report). Nothing without frames.
void write_flesh_cache(const Flesh& flesh, const std::filesystem::path& out, double fps, const RunResult& result, json& stats) {
  std::vector<UsdMesh> meshes{{.name = "flesh", .triangles = flesh.model.triangles, .frames = {}, .normals = {}, .uv = flesh.model.uv,
                               .converged = {}},
                              {.name = "linear_blend_skinning", .triangles = flesh.model.triangles, .frames = {}, .normals = {},
                               .uv = flesh.model.uv, .converged = {}}};
  const auto add = [&](UsdMesh& mesh, const std::filesystem::path& file) {
    mesh.frames.push_back(read_surface(file).vertices);
    mesh.normals.push_back(surface_normals(flesh, mesh.frames.back()));  // of the surface as it is in the frame
  };
  for (int i = 0; std::filesystem::exists(out / "surface" / frame_name(i)) && std::filesystem::exists(out / "lbs" / frame_name(i)); ++i) {
    add(meshes[0], out / "surface" / frame_name(i));
    add(meshes[1], out / "lbs" / frame_name(i));
  }
  if (meshes[0].frames.empty()) return;
  // A frame that did not converge, which a --keep-going run went past, is marked on the flesh.
  meshes[0].converged.assign(meshes[0].frames.size(), true);
  for (const StepRecord& r : result.records)
    if (!r.converged && r.index >= 0 && static_cast<std::size_t>(r.index) < meshes[0].converged.size()) meshes[0].converged[r.index] = false;
  const RiggedModel& m = flesh.model;
  write_usda(out / "flesh.usda", "character", meshes, fps, m.meters_per_unit, m.up_axis == 2 && m.up_sign > 0 ? 'Z' : 'Y');
  stats["usd"] = "flesh.usda";
  // The same frames as point caches for tools without USD (Blender's Mesh Cache modifier): sample k at frame k.
  write_pc2(out / "flesh.pc2", meshes[0].frames);
  write_pc2(out / "lbs.pc2", meshes[1].frames);
  stats["pc2"] = {{"flesh", "flesh.pc2"}, {"linear_blend_skinning", "lbs.pc2"}};
  // A character in several meshes: a cache per mesh too, as each is its own object in the user's tool.
  const std::vector<ModelPart>& parts = flesh.model.parts;
  if (parts.size() > 1) {
    json files = json::array();
    for (std::size_t p = 0; p < parts.size(); ++p) {
      std::vector<Eigen::Matrix3Xd> samples;
      for (const Eigen::Matrix3Xd& f : meshes[0].frames) samples.push_back(f.middleCols(parts[p].first_vertex, parts[p].vertices));
      const std::string file = part_cache_name(parts, p);
      write_pc2(out / file, samples);
      files.push_back({{"mesh", parts[p].name}, {"file", file}, {"first_vertex", parts[p].first_vertex}, {"vertices", parts[p].vertices}});
    }
    stats["pc2"]["meshes"] = files;
  }
  // The bones at every frame written: segment ends in world space.
  json names = json::array(), frames = json::array();
  for (const Bone& b : flesh.bones) names.push_back(b.name);
  for (std::size_t i = 0; i < meshes[0].frames.size(); ++i) {
    const double t = static_cast<double>(i) / fps;
    const std::vector<Eigen::Affine3d> world = joint_world(flesh, t);
    json segments = json::array();
    for (const Bone& b : flesh.bones) {
      const Eigen::Vector3d a = world[b.joint] * (flesh.bind_world[b.joint].inverse() * b.a);
      const Eigen::Vector3d c = world[b.joint] * (flesh.bind_world[b.joint].inverse() * b.b);
      segments.push_back({a[0], a[1], a[2], c[0], c[1], c[2]});
    }
    frames.push_back({{"time", t}, {"segments", segments}});
  }
  write_atomically(out / "bones.json", [&](std::ostream& o) { o << json{{"bones", names}, {"frames", frames}}.dump() << "\n"; });
}

}  // namespace

void flesh_time(const Scene& s, const Flesh& flesh, double& end_time, int& frames) {
  const double duration = flesh.clip.duration();
  if (!s.time.end_time && duration > 0.0) end_time = duration;
  if (s.time.frames) return;
  const double fps = s.flesh->fps;  // a flesh body comes from the scene's flesh section
  // Frames on the animation's grid, t = i / fps: the end time rounded up to a whole frame (a clip holds its
  // last key after its end), so a cache's samples fall on the frames of the user's tool.
  if (end_time > 0.0 && end_time * fps < 1.0 - 1e-9)  // its one frame would lie after the end, at 1 / fps
    throw SceneError(fmt::format("{}: fps: {:g} frames per second makes less than one frame of the {:g} s to run; "
                                 "at least {:g} are needed",
                                 s.source.string(), fps, end_time, 1.0 / end_time));
  const double n = std::max(1.0, std::ceil(end_time * fps * (1.0 - 1e-9)));
  if (!(n <= TimeSpec::max_frames))
    throw SceneError(fmt::format("{}: end_time: {:g} s at {:g} frames per second makes {:.3g} frames; at most {} can run",
                                 s.source.string(), end_time, fps, n, TimeSpec::max_frames));
  frames = static_cast<int>(n);
  end_time = n / fps;
}

NewtonOptions flesh_newton_options(const SolverSpec& solver, const Flesh& flesh, const Lame& lame) {
  const double h = flesh.cell_size;
  NewtonOptions o = solver.newton;
  o.max_iterations = solver.max_iterations ? *solver.max_iterations : kFleshNewtonIterations;
  o.tolerance = solver.tolerance ? *solver.tolerance : 1e-6 * youngs_modulus(lame) * h * h;
  o.step_tolerance = solver.step_tolerance ? *solver.step_tolerance : o.tolerance / ((lame.lambda + 2.0 * lame.mu) * h);
  return o;
}

ContactParameters flesh_contact(const ContactSpec& contact, const Flesh& flesh, double youngs) {
  ContactParameters p;
  p.dhat = contact.dhat ? *contact.dhat : flesh_contact_dhat(flesh);
  p.stiffness = contact.stiffness ? *contact.stiffness : flesh_contact_stiffness(flesh, youngs, p.dhat);
  return p;
}

void add_flesh_terms(const BuiltScene& b, SimulationSetup& setup, std::vector<std::shared_ptr<Term>>& bones) {
  const Scene& s = b.scene;
  const std::shared_ptr<const Flesh>& flesh = b.body->flesh;
  if (!is_dynamic(s.time.integrator)) setup.carrier = flesh_carrier(flesh);  // guesses that follow the bones
  if (std::shared_ptr<Term> soft = soft_binding_term(flesh, s.flesh->soft_stiffness, youngs_modulus(s.material.params)))
    setup.terms.push_back(std::move(soft));
  if (s.contact.enabled && s.contact.bones) bones = bone_collider_terms(flesh, b.contact.dhat, b.contact.stiffness);
}

namespace {

/// The render-surface vertex nearest each end joint of the skeleton (a joint without children: a fingertip,
/// a toe, the top of the head) at the bind pose, each vertex once.
std::vector<int> tip_vertices(const RiggedModel& m) {
  std::vector<int> out;
  if (m.vertices.cols() == 0) return out;
  const std::vector<std::vector<int>> children = m.skeleton.children();
  for (int j = 0; j < m.skeleton.size(); ++j) {
    if (!children[static_cast<std::size_t>(j)].empty() || static_cast<std::size_t>(j) >= m.inverse_bind.size()) continue;
    const Eigen::Vector3d at = m.inverse_bind[static_cast<std::size_t>(j)].inverse().block<3, 1>(0, 3);
    Eigen::Index nearest = 0;
    (m.vertices.colwise() - at).colwise().squaredNorm().minCoeff(&nearest);
    if (std::find(out.begin(), out.end(), static_cast<int>(nearest)) == out.end()) out.push_back(static_cast<int>(nearest));
  }
  return out;
}

}  // namespace

void add_flesh_output(const BuiltScene& b, const Simulation& sim, RunPlan& plan) {
  const Flesh& flesh = *b.body->flesh;
  const FleshSpec& spec = *b.scene.flesh;
  plan.table = &flesh_table();
  add_flesh_settings(flesh, spec, plan.settings);
  if (b.scene.contact.enabled) {  // the bones with a capsule collider (add_flesh_terms)
    std::vector<std::vector<int>> points;
    if (b.scene.contact.bones) points = bone_collider_points(flesh, b.contact.dhat);
    plan.settings["contact"]["bone_colliders"] =
        std::count_if(points.begin(), points.end(), [](const std::vector<int>& p) { return !p.empty(); });
  }
  std::vector<double> times;  // the frames' times, as the run records them (frame i at i · frame_duration)
  for (int i = 1; i <= plan.frames; ++i) times.push_back(i * plan.frame_duration);
  const PressedFlesh pressed = pressed_flesh(b.body->flesh, times);
  plan.settings["pressed_flesh"] = nullptr;
  if (pressed.frame >= 0)
    plan.settings["pressed_flesh"] = {{"frames", pressed.frames}, {"worst_frame", pressed.frame + 1}, {"time", pressed.time},
                                      {"bones", {flesh.bones[pressed.bone_a].name, flesh.bones[pressed.bone_b].name}},
                                      {"rest_distance", pressed.rest}, {"closest", pressed.closest}};
  std::vector<std::string> warnings = flesh_warnings(flesh, pressed);
  plan.warnings.insert(plan.warnings.end(), warnings.begin(), warnings.end());
  const auto base_header = plan.header;
  plan.header = [&flesh, &spec, base_header, warnings = std::move(warnings)](std::ostream& o) {
    write_flesh_header(flesh, spec, o);
    for (const std::string& w : warnings) o << "warning: " << w << "\n";
    if (base_header) base_header(o);
  };
  const double rest_surface = surface_volume(flesh, flesh.model.vertices);
  const auto base_fill = plan.fill;
  std::vector<int> tips = tip_vertices(flesh.model);
  plan.fill = [&flesh, &sim, rest_surface, base_fill, tips = std::move(tips)](StepRecord& r, const StepReport* rep) {
    if (base_fill) base_fill(r, rep);
    const Eigen::Matrix3Xd skin = flesh_surface(flesh, sim.x()), lbs = skinned_surface(flesh, r.time);
    r.surface_volume_ratio = surface_volume(flesh, skin) / rest_surface;
    r.lbs_volume_ratio = surface_volume(flesh, lbs) / rest_surface;
    r.lbs_distance = (skin - lbs).colwise().norm().maxCoeff();
    r.tip_distance = 0.0;
    for (int v : tips) r.tip_distance = std::max(r.tip_distance, (skin.col(v) - lbs.col(v)).norm());
  };
  const std::filesystem::path out = plan.out;
  plan.write_frame = [&flesh, out](int index, double time, const Eigen::VectorXd& x, const std::string& prefix) {
    ensure_writable_directory(out / "surface");
    ensure_writable_directory(out / "lbs");
    // The model's texture coordinates, and the normals of the surface as it is in each frame.
    const RiggedModel& m = flesh.model;
    const Eigen::Matrix3Xd skin = flesh_surface(flesh, x), lbs = skinned_surface(flesh, time);
    write_obj(out / "surface" / (prefix + frame_name(index)), skin, m.uv, surface_normals(flesh, skin), m.triangles);
    write_obj(out / "lbs" / (prefix + frame_name(index)), lbs, m.uv, surface_normals(flesh, lbs), m.triangles);
    if (prefix.empty())
      for (const char* sub : {"surface", "lbs"}) remove_failed_frame(out / sub, index, {".obj"});
  };
  // The grid's own rate where the frames were put on it (flesh_time), exactly; else what the scene's frames make.
  const double fps = b.scene.time.frames ? b.frames / b.end_time : spec.fps;
  plan.finish = [&flesh, out, fps](const RunResult& result, json& stats) { write_flesh_cache(flesh, out, fps, result, stats); };
}

}  // namespace snh
