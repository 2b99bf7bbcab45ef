#pragma once
// A stepping simulation (docs/design.md), with no files: a mesh with its materials, kinematic sets whose
// targets come from providers, and an integrator, solved by projected Newton on a Problem of energy terms
// (elasticity, then inertia, damping and gravity). step(t) makes one solve to time t; advance() a frame
// of equal substeps. Frames, stats and checkpoints are the driver's (driver.hpp).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/dof_map.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/fem/problem.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/sim/dynamics.hpp"
#include "snh/sim/kinematics.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/newton.hpp"

namespace snh {

/// backward_euler, bdf2 and tr_bdf2 are dynamic (inertia over a time step dt); quasi_static solves for equilibrium.
/// BDF2 (docs/math.md §7.5) is second order: it keeps the motion that backward Euler damps. Its first step, and
/// any step more than twice the one before (after a step split for contact), is a backward Euler step.
/// TR-BDF2 (§7.7) is second order from the first step and needs no history: each step is a trapezoidal stage
/// to t_n + γh (γ = 2 − √2), then a BDF2 stage through x_n and that stage's state; two solves a step.
enum class Integrator { backward_euler, bdf2, quasi_static, tr_bdf2 };

/// The integrator's name in scenes, the command line and Python ("backward_euler", "bdf2", "tr_bdf2", "quasi_static").
[[nodiscard]] const char* integrator_name(Integrator i);
/// The integrator of that name; std::nullopt for another word.
[[nodiscard]] std::optional<Integrator> integrator_named(std::string_view name);
[[nodiscard]] inline bool is_dynamic(Integrator i) { return i != Integrator::quasi_static; }

struct SimulationSetup {
  VolumeMesh mesh;
  std::vector<AnyMaterial> materials;     ///< one, or one per material_of_cell index
  std::vector<int> material_of_cell;      ///< empty: materials[0] everywhere
  Eigen::VectorXd weight_scale;           ///< per cell (empty: 1)
  double density = 1.0;
  Integrator integrator = Integrator::quasi_static;
  double dt = 0.0;                        ///< dynamic: the length of every step(t)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double mass_damping = 0.0, stiffness_damping = 0.0;
  std::vector<KinematicSet> kinematic;
  /// Further energy terms (soft bone bindings; contact next), summed after elasticity and inertia in this
  /// order; each is told the time of every solve (Term::at_time) before it starts.
  std::vector<std::shared_ptr<Term>> terms;
  Eigen::VectorXd initial;                ///< 3 #V starting positions (empty: the rest positions)
  Eigen::VectorXd initial_velocity;       ///< dynamic: 3 #V starting velocities (empty: at rest)
  LinearSolverOptions linear;
  NewtonOptions newton;
  /// Dynamic: a time step whose solve does not converge is retried from its start as two halves, each
  /// retried the same way, down to dt / 2^step_halvings (0: a failed solve fails the step). An impact that a
  /// whole step cannot take (a body moving its own size in one step) is then taken in smaller ones.
  int step_halvings = 4;
  /// Quasi-static: the guess of the first step (default: the current state), given the state and t;
  /// kinematic targets are placed on it afterwards.
  std::function<Eigen::VectorXd(const Eigen::VectorXd& x, double t)> first_guess;
  /// The guess when the predicted one leaves an energy's domain (default: the last state), given the last
  /// state and t; kinematic targets are placed on it afterwards.
  std::function<Eigen::VectorXd(const Eigen::VectorXd& x, double t)> fallback_guess;
  /// Quasi-static guesses after the first: 1, the linear extrapolation from the last two solutions; 2, also
  /// the quadratic one from the last three, taken where its energy is lower (scenes and flesh: fewer Newton
  /// and CG iterations on the hand's fist; docs/results.md).
  int extrapolation = 1;
  /// Quasi-static, optional: an affine frame per vertex (3 by 4, x ↦ A x + b) that carries the solution
  /// along at time t (flesh: the model's joints' motions from rest, blended per vertex with skin weights).
  /// With it, the guesses also include the extrapolations made in these frames' coordinates (the last
  /// state carried from its time to t; the linear and quadratic extrapolations of the carried states),
  /// and the lowest energy among all decides: at a keyframe's kink the bones turn, and the flesh with them.
  std::function<void(double t, std::vector<Eigen::Matrix<double, 3, 4>>& frames)> carrier;
  /// Muscle cells (ElasticTerm::set_fibres): #C indices into `fibres`, −1 for a cell without (empty: none).
  std::vector<int> fibre_of_cell;
  std::vector<CellFibre> fibres;
  /// Optional: the fibres' active strain over time. Given t, it sets alpha[f] = γ · activation ∈ [0, 1) for
  /// each entry of `fibres` (alpha holds the values of the last call, zeros at first); called at the start,
  /// before each solve and when a state is restored. Empty: each entry's own active strain throughout.
  std::function<void(double t, std::vector<double>& alpha)> fibre_strain;
};

/// The kinematic flag of every DOF (3 #V) of these sets. Throws std::invalid_argument (one line, naming
/// the sets) for a set without a provider, a vertex out of range, or a coordinate held by two sets.
[[nodiscard]] std::vector<std::uint8_t> kinematic_dof_flags(const std::vector<KinematicSet>& sets, Eigen::Index vertices);

/// One solve, or a frame of substeps.
struct StepReport {
  bool converged = true;
  bool interrupted = false;     ///< NewtonOptions::should_stop stopped it; the state is back where it started
  int substeps = 0;             ///< substeps completed (or tried, for a failure)
  /// Times a step was cut short because a moving collider's sweep or a scripted pin's jump to the step's
  /// time was not clear of the surface (each half solved on its own; summed over the substeps).
  int splits = 0;
  /// Times a step was retried as two halves after its solve failed (SimulationSetup::step_halvings): each
  /// adds one time step to the frame (summed over the substeps). The failed attempts' Newton work is counted.
  int halvings = 0;
  /// Newton's counts and times summed over the substeps, with the largest final residual, the last
  /// solve's energy and every residual, substep after substep.
  NewtonReport newton;
  // Where a solve failed:
  int failed_substep = 0;       ///< 1-based
  double failed_time = 0.0;
  std::string failure;          ///< Newton's reason and the worst element ("; worst element E (min det F = J)")
};

/// The state a checkpoint holds.
struct SimulationState {
  Eigen::VectorXd x;    ///< positions (3 #V)
  /// Backward Euler and TR-BDF2: the velocity (3 #V numbers). BDF2: the velocity, then once a step is made the previous
  /// positions, the previous velocity and the last step's length (9 #V + 1). Quasi-static: the previous
  /// solution (extrapolation), followed by the one before it where the setup's extrapolation is 2 and there
  /// is one (3 #V or 6 #V numbers).
  Eigen::VectorXd aux;
  double time = 0.0;
  int steps = 0;        ///< solves completed
};

class Simulation {
 public:
  /// Throws std::invalid_argument (one line) for inconsistent input: a kinematic vertex out of range, one
  /// DOF driven by two sets, sizes that do not match.
  explicit Simulation(SimulationSetup setup);
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  /// One step to time t: backward Euler, BDF2 or TR-BDF2 (two solves) over dt from the current state, or a quasi-static solve with the
  /// kinematic targets at t. Newton's on_iteration/should_stop come from `newton` (else the setup's).
  /// With contact terms, the step from time() to t is first checked: each term's sweep (a moving collider
  /// from its pose at time() to its pose at t) and the scripted pins' jump to their targets at t (the
  /// terms' max_step, colliders at their pose at t) against the current state. A step not clear is cut
  /// (time and, when dynamic, dt) to the fraction found clear, checked again, solved, and the rest
  /// of the step done likewise from there (report.splits counts the cuts); a part below a millionth of the
  /// step fails with one line (a script driving the surface into a collider).
  StepReport step(double t, const NewtonOptions* newton = nullptr);
  /// `substeps` solves at t_start + k·h, k = 1 … substeps (h = the setup's dt when dynamic); stops at
  /// the first that fails. An interrupted frame returns to the state it started from.
  ///   on_substep  called before each substep with its number (progress lines)
  StepReport advance(double t_start, double h, int substeps, const NewtonOptions* newton = nullptr,
                     const std::function<void(int substep)>& on_substep = {});

  [[nodiscard]] const Eigen::VectorXd& x() const { return x_; }
  [[nodiscard]] const Eigen::VectorXd& v() const { return v_; }
  [[nodiscard]] double time() const { return time_; }
  [[nodiscard]] int steps() const { return steps_; }
  [[nodiscard]] bool dynamic() const { return is_dynamic(setup_.integrator); }
  [[nodiscard]] SimulationState state() const;
  /// Continues from a saved state (sizes checked).
  void restore(const SimulationState& s);

  [[nodiscard]] const VolumeMesh& mesh() const { return elastic_.mesh(); }
  [[nodiscard]] const ElasticTerm& elastic() const { return elastic_; }
  [[nodiscard]] const TimeStepTerm& inertia() const { return inertia_; }
  [[nodiscard]] Problem& problem() { return problem_; }
  /// The linear solver (its name() is the one \"auto\" chose).
  [[nodiscard]] const LinearSolver& solver() const { return *solver_; }
  /// The setup (its mesh moved into the elastic term: mesh(); its initial positions into x()).
  [[nodiscard]] const SimulationSetup& setup() const { return setup_; }
  /// Whether any of the further terms is a contact term (Term::reports_contact).
  [[nodiscard]] bool has_contact() const;
  /// Per vertex: true if any of its DOFs is kinematic.
  [[nodiscard]] std::vector<bool> kinematic_vertices() const;
  /// Sets the kinematic DOFs of `state` to their targets at time t.
  void place_kinematic(Eigen::VectorXd& state, double t) const;
  /// The rest volume (Σ of the cells' weights).
  [[nodiscard]] double rest_volume() const { return rest_volume_; }

 private:
  /// step(t) over a time step h, retried in halves where it fails (`level` halvings deep so far).
  StepReport step_halving(double t, double h, const NewtonOptions* newton, int level);
  /// step(t) over a time step h, split where a collider's sweep is not clear.
  StepReport step_split(double t, double h, const NewtonOptions* newton);
  /// One step to time t over a time step h (dynamic; ignored quasi-statically): one solve, or TR-BDF2's two.
  StepReport solve(double t, double h, const NewtonOptions* newton);
  /// What a solve is: a whole step of the integrator, or one of TR-BDF2's stages.
  enum class Stage { whole, trapezoid, second };
  /// One solve to time t over h as `stage` says.
  StepReport solve_stage(double t, double h, const NewtonOptions* newton, Stage stage);
  /// TR-BDF2's f_n: the force at the current state of every term but inertia (−their gradient, every DOF),
  /// the terms at the current time; a lagged term's (friction) taken for the stage ending at t_stage, at the
  /// slip that the current velocity makes over that stage.
  [[nodiscard]] Eigen::VectorXd start_force(double t_stage);
  /// A dynamic step of length h from the current state as an incremental potential (dynamics.hpp): the
  /// velocity after it is (x − anchor)/h_eff, and predicted = anchor + h_eff v̂ is its inertial target and
  /// the solve's guess (TR-BDF2's trapezoidal stage: the guess x_n + h v_n; its target needs the forces).
  struct Stepper {
    Eigen::VectorXd anchor, predicted;
    double h_eff = 0.0;
  };
  [[nodiscard]] Stepper stepper(double h, Stage stage = Stage::whole) const;
  /// The smallest fraction of the step from `from` to `to` (over h, dynamic) that the moving terms'
  /// sweeps (against the pins' jump and the inertial prediction) and the other terms' bounds on the pins'
  /// jump keep clear.
  double clearance(double from, double to, double h);
  /// Quasi-static with a carrier and a moving collider (a flesh's bones' capsules): the free vertices are
  /// taken along with the carrier (not held still) in the step's check and as the guess's base.
  [[nodiscard]] bool carried_check() const;
  /// Quasi-static with a carrier: the extrapolations made in the carrier's frames (x_n carried to t, and
  /// the linear and quadratic ones from the states before), each taken as the guess where its energy is
  /// lower than E (guess and E updated); returns x_n carried to t.
  Eigen::VectorXd carried_guesses(double t, const Eigen::VectorXd& x_n, Eigen::VectorXd& guess, double& E);
  /// The fibres' active strain at time t (setup.fibre_strain), set where it changed.
  void activate(double t);
  /// x carried by the carrier's frames from time `from` to `to` (every vertex: frame(to) · frame(from)⁻¹).
  [[nodiscard]] Eigen::VectorXd carry(const Eigen::VectorXd& x, double from, double to) const;
  SimulationSetup setup_;
  ElasticTerm elastic_;
  DofMap dofs_;
  TimeStepTerm inertia_;
  Problem problem_;
  std::unique_ptr<LinearSolver> solver_;
  Eigen::VectorXd x_, v_, previous_, previous2_;  // previous2_: empty until known
  // BDF2's history: previous_ is x_{n−1}; v_previous_ is v_{n−1}; h_previous_ the last step's length (0: none).
  Eigen::VectorXd v_previous_;
  double h_previous_ = 0.0;
  Eigen::VectorXd trapezoid_force_;  ///< TR-BDF2: start_force() of the step being made
  double time_ = 0.0;
  int steps_ = 0;  ///< solves completed (a TR-BDF2 step, of two solves, counts once)
  double rest_volume_ = 0.0;
  std::vector<double> alpha_;  ///< per fibres entry, the active strain's α set last (fibre_strain)
};

}  // namespace snh
