#pragma once
// Scenes (DESIGN.md sim/): a JSON file describing a mesh, a material, an integrator, pins with scripted
// motion and an initial deformation, run by `snh run SCENE.json`. The format is in the README
// ("Scene files"); every key is checked, and an unknown key or a bad value is an error that names it.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json_fwd.hpp>

#include "snh/material/lame.hpp"
#include "snh/mesh/box.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/newton.hpp"

namespace snh {

/// A scene file that cannot be used; the message is one line: "FILE: KEY: what is wrong".
class SceneError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Vertices chosen by an axis-aligned box (inclusive, to a 1e-9 relative tolerance) or by index.
struct Selection {
  std::optional<Eigen::AlignedBox3d> region;
  std::vector<int> indices;
};

/// A scripted motion of a pin set, applied with progress p = clamp((t − start)/(end − start), 0, 1).
struct Motion {
  enum class Kind { translate, rotate, scale } kind = Kind::translate;
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();  ///< translate: offset; rotate: axis; scale: factors
  double angle = 0.0;                                ///< rotate: radians
  std::optional<Eigen::Vector3d> center;             ///< rotate / scale (default: the set's centroid)
  double start = 0.0, end = 0.0;
};

struct PinSet {
  Selection select;
  std::array<bool, 3> axes{true, true, true};  ///< the coordinates held (x, y, z); the others slide freely
  std::vector<Motion> motions;  ///< composed in order
};

/// One operation of the initial deformation, applied to the rest positions in order.
struct InitialOp {
  enum class Kind { scale, reflect, collapse, perturb, move } kind = Kind::scale;
  Eigen::Vector3d vector = Eigen::Vector3d::Ones();  ///< scale: factors; move: offset
  int axis = 0;                                      ///< reflect: mirror axis; collapse: see below
  enum class To { plane, line, point } to = To::point;  ///< collapse: plane ⟂ axis, line along axis, or point
  double amplitude = 0.0;                            ///< perturb: uniform in [−a, a] per coordinate
  std::uint64_t seed = 1;                            ///< perturb
  std::optional<Eigen::Vector3d> center;             ///< scale / reflect / collapse (default: bounding-box centre)
  Selection select;                                  ///< move
};

enum class Integrator { backward_euler, quasi_static };

struct Scene {
  std::filesystem::path source;  ///< the file, for messages and stats
  std::string settings;          ///< the parsed file, canonical (checkpoint fingerprint); empty if built in code
  bool resume = false;           ///< continue the run in `out` from its checkpoint (the last completed frame)
  std::string command_line;      ///< as the user typed it, for stats.json and the report
  // Mesh: a file (mesh_file, relative paths resolved against the scene file's directory), or else a box
  // of tets or hexes spanning [box_min, box_max].
  std::filesystem::path mesh_file;
  CellType element = CellType::hex8;
  int resolution = 4;
  TetSplit tet_split = TetSplit::paper;
  Eigen::Vector3d box_min = Eigen::Vector3d::Constant(-1.0), box_max = Eigen::Vector3d::Constant(1.0);
  // Material.
  std::string material = "stable_neo_hookean";
  Lame params{1.0, 10.0};
  bool reparametrize = false;
  double density = 1.0;
  // Time.
  Integrator integrator = Integrator::backward_euler;
  double dt = 0.01;        ///< backward Euler: the largest substep (each frame is split into equal substeps)
  double end_time = 1.0;
  int frames = 25;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double mass_damping = 0.0, stiffness_damping = 0.0;
  std::vector<PinSet> pins;
  std::vector<InitialOp> initial;
  // Solver.
  std::string solver = "cholmod";            ///< a linear_solvers() name
  bool reuse_factor = true;
  NewtonOptions newton;  ///< tolerance 1e-6 on ‖g‖ unless the file says otherwise
  // Output.
  std::filesystem::path out;  ///< default output/<file stem>
  bool write_vtu = true;
};

/// Reads and checks a scene file. Throws SceneError.
[[nodiscard]] Scene load_scene(const std::filesystem::path& file);
/// Checks a parsed scene; `source` names it in messages. Throws SceneError.
[[nodiscard]] Scene parse_scene(const nlohmann::json& j, const std::filesystem::path& source);

/// The mesh of a scene: its mesh file (read and checked; `reoriented` gets the count of inverted cells
/// turned round), or a box of its element type scaled to its bounds. Throws MeshError for a bad file.
[[nodiscard]] VolumeMesh scene_mesh(const Scene& scene, int* reoriented = nullptr);
/// The initial positions: the rest positions with scene.initial applied (3 #V).
[[nodiscard]] Eigen::VectorXd initial_positions(const Scene& scene, const VolumeMesh& mesh);

struct FrameStats {
  int frame = 0;
  double time = 0.0;
  int substeps = 0;
  bool converged = true;
  int newton_iterations = 0, line_search_steps = 0, linear_iterations = 0, factorizations = 0;
  double residual = 0.0;  ///< the largest final ‖g‖ of the frame's substeps
  double elastic_energy = 0.0, kinetic_energy = 0.0, gravity_energy = 0.0;
  double total_energy = 0.0;  ///< elastic + kinetic + gravity
  double volume_ratio = 1.0, min_J = 1.0;
  int inverted = 0;
  double wall_seconds = 0.0;
  std::string failure;
};

struct SceneResult {
  std::vector<FrameStats> frames;  ///< frame 0 is the initial state
  bool all_converged = true;
  std::string failure;             ///< why the run stopped early (empty when it ran to the end)
  int interrupted_by = 0;          ///< the signal (SIGINT, SIGTERM) that stopped the run; 0 if none
  double total_seconds = 0.0, peak_memory_mib = 0.0;
  CellType element = CellType::hex8;
  Eigen::Index vertices = 0, cells = 0;
  Eigen::VectorXd final_positions;
};

/// Runs the scene: writes NNN.obj / NNN.vtu frames, frames.pvd, stats.json and stats.csv into scene.out,
/// printing a header and one line per frame to log (live_progress: update a line per Newton iteration).
/// Stops at the first substep that fails (its frame and the stats are still written). A starting state
/// outside the energy's domain stops the run at frame 0 with that reason.
[[nodiscard]] SceneResult run_scene(const Scene& scene, std::ostream& log, bool live_progress = false);

}  // namespace snh
