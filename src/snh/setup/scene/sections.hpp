#pragma once
// The scene's section parsers (internal to setup/), one file each: every one reads its keys from the
// top-level object (or its own sub-object) and starts from its struct's defaults.
#include <filesystem>
#include <stdexcept>
#include <optional>
#include <vector>

#include "snh/setup/scene.hpp"
#include "snh/setup/scene/keys.hpp"

namespace snh::scene {

/// f(), with a bad-input error from below (a rig, a kinematic set, a term) turned into a SceneError of the same
/// line.
template <class F>
auto as_scene_error(F&& f) {
  try {
    return f();
  } catch (const SceneError&) {
    throw;
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
}

/// "mesh": {"box": {...}} or {"file": "..."} (relative to the scene file's directory).
[[nodiscard]] MeshSpec parse_mesh(Keys& top, const std::filesystem::path& source);
/// "flesh": a rigged model (relative to the scene file's directory), its volume, animation and bone radii.
[[nodiscard]] std::optional<FleshSpec> parse_flesh(Keys& top, const std::filesystem::path& source);
/// "material" and "density", from `defaults` where the scene gives none (a flesh scene's differ).
[[nodiscard]] MaterialSpec parse_material(Keys& top, const MaterialSpec& defaults);
/// A material object ({name, mu and lambda or youngs and poisson, reparametrize}) at `path`, from `defaults`
/// where it gives no value.
[[nodiscard]] MaterialChoice parse_material_object(const json& j, const std::string& path, const std::string& file,
                                                   const MaterialChoice& defaults);
/// "tissues" and "muscles" (regions' mesh files relative to the scene file's directory, read by the build).
[[nodiscard]] std::vector<MuscleSpec> parse_muscles(Keys& top, const std::filesystem::path& source, bool flesh);
/// "integrator", "dt", "end_time", "frames".
[[nodiscard]] TimeSpec parse_time(Keys& top);
/// "gravity" and "damping".
[[nodiscard]] ForceSpec parse_forces(Keys& top);
/// A selection's "region" or "indices" in the object k reads.
[[nodiscard]] Selection parse_selection(Keys& k);
/// "pins" (motions default to ending at end_time).
[[nodiscard]] std::vector<PinSpec> parse_pins(Keys& top, double end_time);
/// One motion object of a "motion" array (pins, colliders) at `path` (its end defaults to end_time).
[[nodiscard]] Motion parse_motion(const json& j, const std::string& path, const std::string& file, double end_time);
/// "initial".
[[nodiscard]] std::vector<InitialOp> parse_initial(Keys& top);
/// "solver".
[[nodiscard]] SolverSpec parse_solver(Keys& top);
/// "contact" and "colliders" (a stiffness left out or "auto" is chosen by the build; mesh files relative to the scene
/// file's directory, named here and read by read_collider_mesh; motions default to ending at end_time).
[[nodiscard]] ContactSpec parse_contact(Keys& top, const std::filesystem::path& source, double end_time);
/// A mesh collider's surface file read into its vertices and triangles. Throws SceneError naming `file` (the
/// scene) and the collider: the file cannot be read, has no triangles, a coordinate beyond max_magnitude or a
/// degenerate triangle.
void read_collider_mesh(ColliderSpec& c, const std::string& file);
/// "output" (the directory defaults to output/<file stem>).
[[nodiscard]] OutputSpec parse_output(Keys& top, const std::filesystem::path& source);

}  // namespace snh::scene
