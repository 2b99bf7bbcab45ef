#include "flesh_command.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <omp.h>

#include "../common/out_option.hpp"
#include "parameter_options.hpp"
#include "run_command.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/rig/model.hpp"
#include "snh/setup/flesh_scene.hpp"
#include "snh/setup/scene_build.hpp"

namespace snh::cli {
namespace {

/// `snh flesh MODEL --list`: what the model holds, for choosing a clip or a joint by name.
void list_model(const std::string& file, std::ostream& o) {
  const RiggedModel m = read_model(file);
  const EdgeCounts edges = edge_counts(m.surface_triangles);
  o << fmt::format("model {} ({}): {} vertices ({} welded), {} triangles, {} open and {} non-manifold edges\n", file, m.format, m.vertices.cols(),
                   m.surface_vertices.cols(), m.triangles.cols(), edges.open, edges.non_manifold);
  for (const std::string& note : m.notes) o << "note: " << note << "\n";
  o << fmt::format("skinned meshes ({}):\n", m.parts.size());
  for (const ModelPart& p : m.parts) o << fmt::format("  {}: {} vertices\n", p.name, p.vertices);
  for (const std::string& s : m.skipped) o << fmt::format("  {}: not read (bound to another skin)\n", s);
  o << fmt::format("joints ({}, hierarchy from the {}):\n", m.skeleton.size(), m.hierarchy == "names" ? "joint names" : "file");
  const std::vector<std::vector<int>> children = m.skeleton.children();
  std::vector<std::pair<int, int>> stack;  // joint, depth
  for (int j = m.skeleton.size() - 1; j >= 0; --j)
    if (m.skeleton.joints[static_cast<std::size_t>(j)].parent < 0) stack.emplace_back(j, 0);
  while (!stack.empty()) {
    const auto [j, depth] = stack.back();
    stack.pop_back();
    o << fmt::format("  {:{}}{}\n", "", 2 * depth, m.skeleton.joints[static_cast<std::size_t>(j)].name);
    const std::vector<int>& c = children[static_cast<std::size_t>(j)];
    for (auto it = c.rbegin(); it != c.rend(); ++it) stack.emplace_back(*it, depth + 1);
  }
  const int chosen = default_clip(m);
  o << fmt::format("clips ({}):\n", m.clips.size());
  for (std::size_t c = 0; c < m.clips.size(); ++c)
    o << fmt::format("  {}: \"{}\", {:g} s, {} channels{}\n", c, m.clips[c].name, m.clips[c].duration(), m.clips[c].channels.size(),
                     static_cast<int>(c) == chosen ? " (played by default)" : m.clips[c].moves() ? "" : " (does not move)");
}

}  // namespace

void add_flesh_command(CLI::App& app, int& exit_code) {
  struct Options {
    std::string model, animation, volume = "lattice", material = "stable_neo_hookean", out, solver = "auto";
    int resolution = 0, newton_iterations = kFleshNewtonIterations;
    double cell_size = 0.0;
    ParameterOptions params;
    bool quasi_static = false, dynamic = false, resume = false, keep_going = false, no_report = false, force = false;
    double fps = FleshSpec{}.fps;
    double soft_shell = 0.0, soft_stiffness = FleshSpec{}.soft_stiffness, radius_scale = FleshSpec{}.radius_scale;
    std::string joint_cells = to_string(FleshSpec{}.joint_cells);
    std::string integrator = "backward_euler";
    int threads = 0;
    bool self_contact = false, list = false, no_split_cells = false, join_meshes = false;
    double ground = 0.0, dhat = 0.0, contact_stiffness = 0.0, friction = 0.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "flesh",
      "Skeleton-driven flesh (the paper's Figure 1 workflow): fills a rigged model's skin (glTF, or FBX, COLLADA, .x … through assimp) with a "
      "hexahedral lattice or tets, binds the volume vertices inside each bone's capsule to the bone, plays the model's animation "
      "clip and solves the rest of the flesh (quasi-static by default, stable_neo_hookean, nu = 0.488). Writes the render "
      "surface per frame (surface/NNN.obj) beside the same surface posed by linear blend skinning (lbs/NNN.obj), the "
      "volume (NNN.vtu, frames.pvd), flesh.usda, the point caches flesh.pc2 and lbs.pc2 (Blender's Mesh Cache modifier reads them), "
      "stats.json and the report. A model without a clip runs from a scene "
      "file instead (snh run, with keyframes: see scenes/hand_fist.json). Exit code 0 when every frame converged, 1 "
      "when a frame did not converge (the run stopped there, or went on with --keep-going), 2 for bad input.");
  cmd->add_option("model", o->model, "Rigged model: .glb or .gltf (snh's glTF 2.0 reader), or FBX, COLLADA (.dae), DirectX .x and the other formats "
                  "assimp reads")->required();
  cmd->add_option("--animation", o->animation, "The clip to play, by name or 0-based index (default: the first that lasts and moves; --list shows them)");
  cmd->add_option("--volume", o->volume, "lattice (default: hexahedra, as the paper's Figure 1) or tets (TetGen)")
      ->check(CLI::IsMember({"lattice", "tets"}));
  auto* res = cmd->add_option("--resolution", o->resolution,
                               "Cubes along the model's longest side (tets: of that size). Default: chosen from the bones, at "
                               "least 16: cells no wider than 2/sqrt(3) of the thinnest capsule, so that every bone binds flesh "
                               "(capped at about 20 000 cells); the header says why")
                   ->check(CLI::Range(1, 1000));
  cmd->add_option("--cell-size", o->cell_size, "The cubes' edge in model units, instead of --resolution")
      ->check(finite_number(Sign::positive))
      ->excludes(res);
  cmd->add_option("--radius-scale", o->radius_scale,
                  "Scale every bone's capsule radius (default 1: half the mean distance from the bone to the skin nearest "
                  "it). Below 1 where neighbouring capsules press flesh inside out as a joint bends: the run warns, naming "
                  "the bones")
      ->check(finite_number(Sign::positive));
  cmd->add_option("--soft-shell", o->soft_shell,
                                "Bind softly the flesh within this distance outside the bones' capsules (model units): springs "
                                "pull it toward where its bone carries it (default: none, only the capsules' hard binding)");
  cmd->add_option("--soft-stiffness", o->soft_stiffness,
                  "Stiffness of the soft binding's springs (the shell's and the joint cells'), in Young's modulus x cell size "
                  "(default 1: about one cell of flesh)");
  cmd->add_option("--joint-cells", o->joint_cells,
                  "Vertices of the bones' capsules in cells spanning two joints: hard (default: bound, as HOBAK), free "
                  "(released to the solve, so the joint's cells can give: a sharply bent fine lattice then converges), or "
                  "soft (released, and bound by springs of --soft-stiffness instead)")
      ->check(CLI::IsMember({"soft", "free", "hard"}));
  cmd->add_flag("--no-split-cells", o->no_split_cells,
                "One lattice cell per cube even where the skin separates its material (parts closer than a cube, such as "
                "two fingers, are then glued together there); by default such a cube gets a cell per piece");
  cmd->add_flag("--join-meshes", o->join_meshes,
                "Make all the model's meshes one solid; by default meshes whose skins share no joint are separate solids, "
                "each held only by its own joints' bones and glued only at skin vertices they share, so parts that "
                "overlap at rest (a hand sunk into a thigh) are not fused");
  cmd->add_flag("--self-contact", o->self_contact,
                "Self-contact of the render surface (IPC barrier on the welded skin, embedded in the volume: no two of its "
                "triangles pass through each other)");
  cmd->add_option("--ground", o->ground,
                  "A ground plane at height Y (model units) along the model's up axis (+y, or the axis an FBX states) that the render "
                  "surface stays above; it must start above it");
  cmd->add_option("--dhat", o->dhat,
                  "Distance below which contact repels, model units (default: a quarter of the render surface's mean edge "
                  "length, at most half its smallest distance at rest)")
      ->check(finite_number(Sign::positive));
  cmd->add_option("--contact-stiffness", o->contact_stiffness,
                  "Barrier stiffness kappa (default: Young's modulus x cell size / dhat^2, about one cell's stiffness)")
      ->check(finite_number(Sign::positive));
  cmd->add_option("--friction", o->friction,
                  "Coulomb friction coefficient mu of the skin on itself (--self-contact) and on the --ground (default 0: frictionless)")
      ->check(finite_number(Sign::non_negative));
  cmd->add_option("--material", o->material, "Energy (default stable_neo_hookean): " + material_name_list());
  add_parameter_options(cmd, o->params, "--youngs 1e5 --poisson 0.488, the paper's flesh");
  auto* qs = cmd->add_flag("--quasi-static", o->quasi_static, "Quasi-static frames (the default, as the paper)");
  auto* dyn = cmd->add_flag("--dynamic", o->dynamic,
                "Dynamic frames (backward Euler unless --integrator says) with gravity 9.81 m/s^2 down the model's up axis instead (density 1000 kg/m^3; gravity, density and "
                "the material's Pa taken to the model's units where it states them, as an FBX in centimetres does)")
      ->excludes(qs);
  cmd->add_option("--integrator", o->integrator,
                  "With --dynamic: backward_euler (the default; damps the motion strongly), bdf2 (second order: "
                  "flesh that keeps jiggling) or tr_bdf2 (second order from the first step, two solves a step)")
      ->check(CLI::IsMember({"backward_euler", "bdf2", "tr_bdf2"}))
      ->needs(dyn);
  cmd->add_option("--fps", o->fps, "Frames per second of animation (default 24)")->check(finite_number(Sign::positive));
  cmd->add_option("--out", o->out, "Output directory (default output/<model name>)")->check(non_empty_path());
  cmd->add_option("--solver", o->solver, "Linear solver (default auto: by size; see snh stretch --help)");
  cmd->add_option("--newton-iterations", o->newton_iterations,
                  "Newton iterations a frame may take before it counts as not converged (default 200)")
      ->check(CLI::Range(1, 100000));
  cmd->add_flag("--resume", o->resume, "Continue a stopped run in the output directory from its last completed frame");
  cmd->add_flag("--keep-going", o->keep_going,
                "Write a frame that does not converge (marked NOT CONVERGED in its line and in stats.json) and go on from it instead of stopping; the exit code is still 1");
  cmd->add_flag("--force", o->force, "Write into --out even if it is not empty and holds no snh run (files with the names of ours are replaced)");
  cmd->add_flag("--no-report", o->no_report, "Do not write the browser report (index.html; snh report DIR writes it later)");
  cmd->add_option("--threads", o->threads, "OpenMP threads for assembly (default: all cores)")->check(CLI::Range(0, 1024));
  cmd->add_flag("--list", o->list, "Print the model's skinned meshes, joints (as a tree) and clips, and run nothing");
  cmd->callback([o, cmd, &exit_code]() {
    if (o->list) {
      list_model(o->model, std::cout);
      exit_code = 0;
      return;
    }
    // The options become a scene, checked by the same parser as a scene file.
    nlohmann::json j;
    // A dynamic run or a ground needs the model's unit and up axis (an FBX in centimetres, Z up): the options'
    // pressures (Pa), density (kg/m³) and gravity (9.81 m/s² down) are taken to the model's units and axes.
    const bool ground = cmd->count("--ground") > 0;
    double unit = 1.0;                                 // metres per model unit
    Eigen::Vector3d up = Eigen::Vector3d::UnitY();
    if (o->dynamic || ground) {
      const RiggedModel m = read_model(o->model);
      unit = m.meters_per_unit;
      up = m.up_sign * Eigen::Vector3d::Unit(m.up_axis);
    }
    j["flesh"] = {{"model", o->model}, {"volume", o->volume}};
    if (cmd->count("--resolution")) j["flesh"]["resolution"] = o->resolution;
    if (cmd->count("--cell-size")) j["flesh"]["cell_size"] = o->cell_size;
    if (!o->animation.empty()) j["flesh"]["animation"] = o->animation;
    if (cmd->count("--radius-scale")) j["flesh"]["radius_scale"] = o->radius_scale;
    if (cmd->count("--soft-shell")) j["flesh"]["soft_binding"]["shell"] = o->soft_shell;
    if (cmd->count("--soft-stiffness")) j["flesh"]["soft_binding"]["stiffness"] = o->soft_stiffness;
    j["flesh"]["joint_cells"] = o->joint_cells;
    if (o->no_split_cells) j["flesh"]["split_cells"] = false;
    if (o->join_meshes) j["flesh"]["join_meshes"] = true;
    nlohmann::json material = {{"name", o->material}};
    if (cmd->count("--youngs") || cmd->count("--poisson")) {
      (void)o->params.lame();  // checks that they go together
      material["youngs"] = o->params.youngs * unit;
      material["poisson"] = o->params.poisson;
    } else if (cmd->count("--mu") || cmd->count("--lambda")) {
      if (!cmd->count("--mu") || !cmd->count("--lambda")) throw ParameterError("--mu and --lambda go together for snh flesh");
      material["mu"] = o->params.mu * unit;
      material["lambda"] = o->params.lambda * unit;
    } else {
      const Lame p = lame_from_youngs(FleshSpec::youngs * unit, FleshSpec::poisson);
      material["mu"] = p.mu;
      material["lambda"] = p.lambda;
    }
    material["reparametrize"] = o->params.reparametrize;
    j["material"] = material;
    if (o->dynamic) {
      j["integrator"] = o->integrator;
      const Eigen::Vector3d g = up.unaryExpr([unit](double u) { return u == 0.0 ? 0.0 : -9.81 / unit * u; });  // no −0
      j["gravity"] = {g.x(), g.y(), g.z()};
      j["density"] = FleshSpec::density * unit * unit * unit;
      j["dt"] = 1.0 / o->fps;
    } else {
      j["integrator"] = "quasi_static";
    }
    j["solver"] = {{"linear", o->solver}};
    if (cmd->count("--newton-iterations")) j["solver"]["max_iterations"] = o->newton_iterations;
    if (o->self_contact || ground) {
      j["contact"] = {{"self", o->self_contact}};
      if (cmd->count("--dhat")) j["contact"]["dhat"] = o->dhat;
      if (cmd->count("--contact-stiffness")) j["contact"]["stiffness"] = o->contact_stiffness;
      if (ground) {
        const Eigen::Vector3d point = o->ground * up;
        j["colliders"] = {{{"type", "plane"}, {"point", {point.x(), point.y(), point.z()}}, {"normal", {up.x(), up.y(), up.z()}}}};
      }
      if (cmd->count("--friction")) j["contact"]["friction"] = o->friction;
    } else if (cmd->count("--friction")) {
      throw SceneError("snh flesh: --friction needs --self-contact or --ground");
    } else if (cmd->count("--dhat") || cmd->count("--contact-stiffness")) {
      throw SceneError("snh flesh: --dhat and --contact-stiffness need --self-contact or --ground");
    }
    j["output"] = {{"dir", o->out.empty() ? "output/" + std::filesystem::path(o->model).stem().string() : o->out}};
    // The clip's length (known once the model is read) and --fps decide the frames.
    j["flesh"]["fps"] = o->fps;
    if (o->threads > 0) omp_set_num_threads(o->threads);
    BuiltScene built = build_scene(parse_scene(j, "snh flesh"));
    if (const Clip& clip = built.body->flesh->clip; clip.channels.empty())
      throw SceneError(fmt::format("{}: animation \"{}\" moves none of the skin's joints (its channels animate morph target "
                                   "weights or nodes outside the skin): nothing to play",
                                   o->model, clip.name));
    else if (!(clip.duration() > 0.0))
      throw SceneError(fmt::format("{}: animation \"{}\" has no length (a single key): nothing to play", o->model, clip.name));
    built.scene.source = o->model;
    built.scene.run.program = "snh flesh";
    built.scene.run.resume = o->resume;
    built.scene.run.keep_going = o->keep_going;
    exit_code = run_scene_command(built, o->no_report, o->force);
  });
}

}  // namespace snh::cli
