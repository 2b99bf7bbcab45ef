#pragma once
// Scenes (docs/design.md setup/, docs/scenes.md): a JSON file describing a mesh (or a rigged model's flesh), a
// material, time stepping, forces, pins with scripted motion, an initial deformation, contact and colliders,
// run by `snh run SCENE.json`. A scene goes through three stages:
//   parse (this file: pure, reads no file but the scene's own text) → build (scene_build.hpp: the body read or
//   made, every default that depends on it resolved, everything checked) → run (scene_run.hpp).
// Every key is checked at parse, and an unknown key or a bad value is an error that names it. A Scene is made
// of sections, each with its own parser (setup/scene/*.cpp) and its defaults in its struct, so a Scene built in
// code and one read from JSON mean the same; the keys whose defaults depend on the body (a flesh's clip and
// cell size, a mesh's size and masses) are optional here and resolved by the build, in one place each.
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "snh/material/lame.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/run/run_directory.hpp"
#include "snh/setup/flesh.hpp"
#include "snh/setup/muscle_spec.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/sim/simulation.hpp"
#include "snh/solve/newton.hpp"

namespace snh {

/// A scene file that cannot be used; the message is one line: "FILE: KEY: what is wrong".
class SceneError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// "mesh": a mesh file, or else a box of tets or hexes spanning [min, max].
struct MeshSpec {
  std::filesystem::path file;  ///< relative paths resolved against the scene file's directory
  CellType element = CellType::hex8;
  int resolution = 4;
  TetSplit tet_split = TetSplit::paper;
  Eigen::Vector3d min = Eigen::Vector3d::Constant(-1.0), max = Eigen::Vector3d::Constant(1.0);
};

/// "material" and "density".
struct MaterialSpec : MaterialChoice {
  double density = 1.0;
};

/// "integrator", "dt", "end_time", "frames".
struct TimeSpec {
  Integrator integrator = Integrator::backward_euler;
  double dt = 0.01;                ///< dynamic: the largest substep (each frame is split into equal substeps)
  std::optional<double> end_time;  ///< unset: 1 s, or a flesh scene's clip length
  std::optional<int> frames;       ///< unset: 25, or a flesh scene's end time at flesh.fps frames per second
  static constexpr double default_end_time = 1.0;
  static constexpr int default_frames = 25;
  static constexpr int max_frames = 100000;
};

/// "gravity" and "damping".
struct ForceSpec {
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double mass_damping = 0.0, stiffness_damping = 0.0;
};

/// Vertices chosen by an axis-aligned box (inclusive, to a 1e-9 relative tolerance) or by index.
struct Selection {
  std::optional<Eigen::AlignedBox3d> region;
  std::vector<int> indices;
};

/// One entry of "pins": vertices held on some axes, moved by scripted motions (kinematics.hpp).
struct PinSpec {
  Selection select;
  std::array<bool, 3> axes{true, true, true};  ///< the coordinates held (x, y, z); the others slide freely
  std::vector<Motion> motions;                 ///< composed in order, from the set's positions at t = 0
};

/// One operation of "initial", applied to the rest positions in order. `center` defaults to the
/// bounding-box centre of the positions at that point.
struct ScaleOp {
  Eigen::Vector3d factors = Eigen::Vector3d::Ones();
  std::optional<Eigen::Vector3d> center;
};
struct ReflectOp {
  int axis = 0;
  std::optional<Eigen::Vector3d> center;
};
struct CollapseOp {
  enum class To { plane, line, point } to = To::point;  ///< plane ⟂ axis, line along axis, or point
  int axis = 1;
  std::optional<Eigen::Vector3d> center;
};
struct PerturbOp {
  double amplitude = 0.0;  ///< uniform in [−a, a] per coordinate
  std::uint64_t seed = 1;
};
struct MoveOp {
  Selection select;
  Eigen::Vector3d by = Eigen::Vector3d::Zero();
};
/// Adds a velocity to some vertices (all where no selection is given) at t = 0; dynamic scenes only.
struct VelocityOp {
  std::optional<Selection> select;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
};
using InitialOp = std::variant<ScaleOp, ReflectOp, CollapseOp, PerturbOp, MoveOp, VelocityOp>;

/// "solver".
struct SolverSpec {
  std::string linear = "auto";  ///< a linear_solvers() name ("auto": by size)
  bool refactorize = false;
  /// Dynamic scenes: a time step whose solve fails is retried in halves, this many times deep (0 to 20).
  int step_halvings = 4;
  /// Newton's stopping rule for scenes, scale-aware (the same for any units, density, stiffness or time
  /// step): converged when ‖g‖ < force_fraction · E ℓ² (E ℓ²: the force a unit strain puts on a cell of
  /// size ℓ, the cube root of the mean cell volume; a flesh scene: 1e-6 E h², h its cell size, or a step
  /// under 1e-4 h), or when the Newton step's largest entry is below newton.relative_step_tolerance of how
  /// far the step's solve has moved the vertices, or below their coordinates' rounding (IPC's and PolyFEM's
  /// rule on the step, relative: it stops where rounding keeps ‖g‖ from falling, as with a tiny time step).
  /// A given `tolerance` (on ‖g‖, absolute: the paper programs' rule) replaces the force fraction; a given
  /// `step_tolerance` (a length) the flesh's step rule. The build resolves both (scene_build.hpp).
  std::optional<double> tolerance;
  std::optional<double> step_tolerance;
  /// Newton iterations per solve when given (also in newton.max_iterations); else the paper programs' 50, or
  /// a flesh scene's 200 (a joint bent far can need over 100: flesh_newton_options).
  std::optional<int> max_iterations;
  double force_fraction = 1e-6;
  /// Every other Newton option (the build sets tolerance and step_tolerance from the two above).
  NewtonOptions newton = [] {
    NewtonOptions o;
    o.tolerance = 0.0;
    o.relative_step_tolerance = 1e-8;
    return o;
  }();
};

/// "contact" and "colliders": IPC barriers (fem/contact_term.hpp, fem/collider_term.hpp) on the mesh's
/// boundary surface, or on a flesh's render surface (setup/contact_setup.hpp).
struct PlaneColliderSpec {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  ///< unit length; the surface stays on its side
  int index = 0;                                      ///< in "colliders" (messages)
};
/// A sphere, capsule, box or mesh collider, or a plane with a motion (fem/collider_term.hpp).
struct ColliderSpec {
  enum class Type { plane, sphere, capsule, box, mesh };
  Type type = Type::sphere;
  /// plane: point, unit normal; sphere: centre (a); capsule: the segment a–b; box: centre (a), half extents (b)
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0.0;                  ///< sphere, capsule
  std::filesystem::path file;           ///< mesh: the surface file (read by the build)
  Eigen::Matrix3Xd vertices;            ///< mesh: its vertices and triangles, once read (scene_build.hpp)
  Eigen::Matrix3Xi triangles;
  std::vector<Motion> motions;          ///< composed in order from the pose at t = 0
  int index = 0;                        ///< in "colliders" (messages)
};
struct ContactSpec {
  bool enabled = false;            ///< a "contact" section was given
  bool self = false;               ///< self-contact of the boundary surface
  bool bones = false;              ///< a flesh scene: the bones' capsules keep the skin not bound to them out
  /// The distance below which the barrier acts; unset: a flesh scene's default (flesh_contact_dhat).
  std::optional<double> dhat;
  /// κ; unset: "auto" (ipc_barrier_stiffness on the mesh, its mass and time step), or a flesh scene's default
  /// (flesh_contact_stiffness).
  std::optional<double> stiffness;
  double friction = 0.0;           ///< μ of lagged Coulomb friction against planes and shapes (fem/friction_term.hpp); 0: none
  std::optional<double> friction_velocity;  ///< ε_v: slower slip counts as sticking; unset: 1e-3 of the mesh's diagonal per second
  std::vector<PlaneColliderSpec> planes;    ///< fixed planes
  std::vector<ColliderSpec> colliders;      ///< every other collider (a moving plane too)
};

/// "output".
struct OutputSpec {
  std::filesystem::path dir;  ///< a scene file's default: output/<file stem>
  bool vtu = true;
};

/// How this run is driven (not part of the scene's physics or its fingerprint).
struct RunControl {
  std::string program = "snh run";  ///< the program that runs it (stats.json, the header)
  bool resume = false;         ///< continue the run in output.dir from its checkpoint (the last completed frame)
  bool keep_going = false;     ///< write a frame that does not converge, marked, and go on (RunPlan::keep_going)
  std::string command_line;    ///< as the user typed it, for stats.json and the report
  bool live_progress = false;  ///< the log is a terminal: update a line per Newton iteration
  /// Build the problem, print the run's header, and stop before any frame: nothing is written.
  bool check_only = false;
  /// The lock on the output directory if the caller holds it (run_directory.hpp); null: the run takes it.
  std::shared_ptr<RunDirectoryLock> lock;
};

struct Scene {
  std::filesystem::path source;  ///< the file, for messages and stats
  std::string settings;          ///< the parsed file, canonical (checkpoint fingerprint); empty if built in code
  MeshSpec mesh;
  std::optional<FleshSpec> flesh;  ///< "flesh": the volume of a rigged model, its bones driving it (instead of "mesh")
  MaterialSpec material;
  TimeSpec time;
  ForceSpec forces;
  std::vector<PinSpec> pins;
  std::vector<InitialOp> initial;
  SolverSpec solver;
  ContactSpec contact;
  /// "tissues", then "muscles": regions with their own materials, muscles' fibres and activation (muscle_spec.hpp).
  std::vector<MuscleSpec> muscles;
  OutputSpec output;
  RunControl run;
};

/// Reads and checks a scene file's keys (parse_scene). Throws SceneError.
[[nodiscard]] Scene load_scene(const std::filesystem::path& file);
/// A scene file's text as JSON, strictly: a key given twice in one object, a number beyond double's range
/// (1e309) or nesting over 64 levels is a SceneError naming `file` and the key or line. Also for bad JSON.
[[nodiscard]] nlohmann::json read_scene_json(std::string_view text, const std::string& file);
/// Checks a parsed scene's keys and values; `source` names it in messages and is the directory relative file
/// names are resolved against. Pure: reads no file (the build reads the mesh, model and collider files).
/// Throws SceneError.
[[nodiscard]] Scene parse_scene(const nlohmann::json& j, const std::filesystem::path& source);

}  // namespace snh
