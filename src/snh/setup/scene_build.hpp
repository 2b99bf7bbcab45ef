#pragma once
// A scene built (the second of its three stages, scene.hpp): its body read or made (a mesh file, a box, or a
// rigged model's flesh), every default that depends on the body resolved in one place (the frames and end
// time of a flesh's clip, Newton's tolerances at the body's scale, contact's d̂ and κ), and everything that
// needs the body checked (coordinates, pins, the initial deformation, a separated start for contact). A run
// (scene_run.hpp) starts from a BuiltScene; `snh run`, `snh flesh` and Python build before they touch the
// output directory, so a scene that cannot run writes nothing.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/term.hpp"
#include "snh/setup/contact_setup.hpp"
#include "snh/setup/flesh.hpp"
#include "snh/setup/muscles.hpp"
#include "snh/setup/scene.hpp"
#include "snh/sim/simulation.hpp"

namespace snh {

/// What a scene simulates: a mesh read from a file (and checked), a box, or a flesh's volume.
struct SceneBody {
  VolumeMesh mesh;
  int reoriented = 0;                  ///< inverted cells of the file turned round
  std::string digest;                  ///< the file's contents (checksum.hpp): the mesh's or the model's; empty for a box
  std::shared_ptr<const Flesh> flesh;  ///< a flesh scene's model, volume, embedding and bones
  std::vector<long long> cell_tags;    ///< a mesh file's region tag per cell (MeshFile::cell_tags); empty: none
};
/// The scene's body: its mesh file read, its box made and scaled to its bounds, or its flesh built. Throws
/// MeshError (a bad mesh file), RigError (a bad model) or std::invalid_argument, one line each.
[[nodiscard]] std::shared_ptr<const SceneBody> scene_body(const Scene& scene);

/// A scene ready to run: its body, and its settings with every default resolved.
struct BuiltScene {
  Scene scene;                             ///< as parsed, its mesh colliders' files read
  std::shared_ptr<const SceneBody> body;
  double end_time = 0.0;                   ///< given, or the flesh's clip length, or 1 s
  int frames = 0;                          ///< given, or end_time × fps (rounded up) for flesh, or 25
  int substeps = 1;                        ///< solves per frame (dynamic: no longer than dt each)
  double substep = 0.0;                    ///< their length
  NewtonOptions newton;                    ///< the solver section's, its tolerances at the body's scale
  ContactParameters contact;               ///< d̂, κ, friction, ε_v (where contact is enabled)
  std::string contact_stiffness_rule;      ///< how κ came about ("given", or the rule that chose it), for the header
  Eigen::VectorXd x0;                      ///< the rest positions with the initial operations applied
  Eigen::VectorXd v0;                      ///< the velocities at t = 0 (the initial velocity operations; 3 #V)
  std::shared_ptr<const BuiltMuscles> muscles;  ///< the tissues and muscles (null: none)
};

/// Builds and checks a parsed scene (see the header). Throws SceneError (one line naming the scene file and
/// the key or value at fault), MeshError for a bad mesh file.
[[nodiscard]] BuiltScene build_scene(const Scene& scene);

/// The surface contact acts on: a flesh's render surface, else the mesh's boundary.
[[nodiscard]] ContactSurface contact_surface_of(const SceneBody& body);

/// The Newton options a volume scene's solver section means on its mesh and material (Young's modulus E):
/// the force fraction turned into a force (SolverSpec), unless a tolerance is given.
[[nodiscard]] NewtonOptions newton_options(const SolverSpec& solver, const VolumeMesh& rest, double youngs);

/// The simulation of a built scene: its mesh, material, integrator, kinematic sets (the pins, a flesh's
/// bones) and terms (a flesh's soft binding, contact), made anew at each call.
[[nodiscard]] SimulationSetup simulation_setup(const BuiltScene& built);

/// The vertices of a selection. Throws SceneError naming `where` when it selects nothing or an index is
/// out of range.
[[nodiscard]] std::vector<int> select_vertices(const Selection& s, const Eigen::Matrix3Xd& X, const std::string& where);
/// The initial positions: the rest positions with scene.initial applied (3 #V).
[[nodiscard]] Eigen::VectorXd initial_positions(const Scene& scene, const VolumeMesh& mesh);
/// The velocities (3 #V) the initial "velocity" operations give; a SceneError for one in a quasi-static scene.
[[nodiscard]] Eigen::VectorXd initial_velocities(const Scene& scene, const VolumeMesh& mesh);
/// The pins as kinematic sets on the body, their motions starting from `x0` (3 #V), and a flesh's bones.
[[nodiscard]] std::vector<KinematicSet> scene_kinematics(const Scene& scene, const SceneBody& body, const Eigen::VectorXd& x0);

}  // namespace snh
