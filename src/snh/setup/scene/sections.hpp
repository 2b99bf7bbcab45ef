#pragma once
// The scene's section parsers (internal to sim/), one file each: every one reads its keys from the
// top-level object (or its own sub-object) and starts from its struct's defaults.
#include <filesystem>
#include <optional>
#include <vector>

#include "snh/setup/scene.hpp"
#include "snh/setup/scene/keys.hpp"

namespace snh::scene {

/// "mesh": {"box": {...}} or {"file": "..."} (relative to the scene file's directory).
[[nodiscard]] MeshSpec parse_mesh(Keys& top, const std::filesystem::path& source);
/// "flesh": a rigged model (relative to the scene file's directory), its volume, animation and bone radii.
[[nodiscard]] std::optional<FleshSpec> parse_flesh(Keys& top, const std::filesystem::path& source);
/// "material" and "density".
[[nodiscard]] MaterialSpec parse_material(Keys& top);
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
/// "contact" and "colliders" ("auto" stiffness only with backward Euler; mesh files relative to the scene
/// file's directory, read here; motions default to ending at end_time).
[[nodiscard]] ContactSpec parse_contact(Keys& top, Integrator integrator, const std::filesystem::path& source, double end_time);
/// "output" (the directory defaults to output/<file stem>).
[[nodiscard]] OutputSpec parse_output(Keys& top, const std::filesystem::path& source);

}  // namespace snh::scene
