#include "snh/sim/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/LU>
#include <fmt/format.h>

namespace snh {
namespace {

/// "; worst element E (min det F = J)": the cell with the smallest det F over its quadrature points, for
/// a failure diagnostic ("" for no cells).
std::string worst_element(const Eigen::VectorXd& min_J) {
  if (min_J.size() == 0) return "";
  Eigen::Index worst = 0;
  for (Eigen::Index c = 1; c < min_J.size(); ++c)  // NaN-aware: a NaN is the worst
    if (std::isnan(min_J[c]) || (!std::isnan(min_J[worst]) && min_J[c] < min_J[worst])) worst = c;
  return fmt::format("; worst element {} (min det F = {:.4g})", worst, min_J[worst]);
}

}  // namespace

const char* integrator_name(Integrator i) {
  switch (i) {
    case Integrator::backward_euler: return "backward_euler";
    case Integrator::bdf2: return "bdf2";
    case Integrator::tr_bdf2: return "tr_bdf2";
    case Integrator::quasi_static: return "quasi_static";
  }
  return "?";
}

std::optional<Integrator> integrator_named(std::string_view name) {
  for (Integrator i : {Integrator::backward_euler, Integrator::bdf2, Integrator::tr_bdf2, Integrator::quasi_static})
    if (name == integrator_name(i)) return i;
  return std::nullopt;
}

std::vector<std::uint8_t> kinematic_dof_flags(const std::vector<KinematicSet>& sets, Eigen::Index vertices) {
  std::vector<std::uint8_t> flags(3 * vertices, 0);
  std::vector<int> owner(3 * vertices, -1);
  for (std::size_t i = 0; i < sets.size(); ++i) {
    const KinematicSet& s = sets[i];
    if (!s.provider) throw std::invalid_argument(fmt::format("{}: no targets for its vertices", s.name));
    for (int v : s.vertices) {
      if (v < 0 || v >= vertices)
        throw std::invalid_argument(fmt::format("{}: vertex index {} is out of range (the mesh has {} vertices)", s.name, v, vertices));
      for (int a = 0; a < 3; ++a) {
        if (!s.axes[a]) continue;
        const std::size_t d = 3 * static_cast<std::size_t>(v) + a;
        if (owner[d] >= 0 && owner[d] != static_cast<int>(i)) {
          // Two sets of one file ("s.json: pins[0]", "s.json: pins[1]") name the file once.
          std::string other = sets[owner[d]].name;
          const std::size_t file_end = s.name.rfind(": ");
          if (file_end != std::string::npos && other.compare(0, file_end + 2, s.name, 0, file_end + 2) == 0)
            other.erase(0, file_end + 2);
          throw std::invalid_argument(fmt::format("{} holds the {} coordinate of vertex {}, which {} already holds: give each "
                                                  "coordinate one motion",
                                                  s.name, char('x' + a), v, other));
        }
        owner[d] = static_cast<int>(i);
        flags[d] = 1;
      }
    }
  }
  return flags;
}

Simulation::Simulation(SimulationSetup setup)
    : setup_(std::move(setup)),
      elastic_(std::move(setup_.mesh), setup_.materials, setup_.material_of_cell, setup_.weight_scale),
      dofs_(kinematic_dof_flags(setup_.kinematic, elastic_.mesh().vertex_count())),
      inertia_(elastic_, dofs_, lumped_mass(elastic_, setup_.density),
               {.dt = is_dynamic(setup_.integrator) ? setup_.dt : 0.0,
                .gravity = setup_.gravity,
                .mass_damping = setup_.mass_damping,
                .stiffness_damping = setup_.stiffness_damping}),
      problem_(dofs_) {
  if (setup_.step_halvings < 0 || setup_.step_halvings > 20)
    throw std::invalid_argument(fmt::format("step_halvings must be from 0 to 20, got {}", setup_.step_halvings));
  if (dynamic() && !(setup_.dt > 0.0 && std::isfinite(setup_.dt)))
    throw std::invalid_argument(fmt::format("{} needs a time step > 0, got {}", integrator_name(setup_.integrator), setup_.dt));
  problem_.add(elastic_);
  // Inertia, damping and gravity: only where there is something to add (a quasi-static run without
  // gravity minimises the elastic energy alone).
  if (dynamic() || setup_.gravity != Eigen::Vector3d::Zero()) problem_.add(inertia_);
  for (const std::shared_ptr<Term>& term : setup_.terms) {
    if (!term) throw std::invalid_argument("simulation: an energy term is missing (null)");
    problem_.add(*term);
  }
  solver_ = make_linear_solver(setup_.linear, {.mesh = &elastic_.mesh(), .free_index = &dofs_.free_index()});
  const Eigen::Index n = 3 * elastic_.mesh().vertex_count();
  if (setup_.initial.size() == 0) x_ = Eigen::Map<const Eigen::VectorXd>(elastic_.mesh().vertices.data(), n);
  else if (setup_.initial.size() != n)
    throw std::invalid_argument(fmt::format("initial positions: expected {} numbers (3 per vertex), got {}", n, setup_.initial.size()));
  else x_ = std::move(setup_.initial);
  v_ = Eigen::VectorXd::Zero(n);
  if (setup_.initial_velocity.size() != 0) {
    if (setup_.initial_velocity.size() != n)
      throw std::invalid_argument(fmt::format("initial velocities: expected {} numbers (3 per vertex), got {}", n, setup_.initial_velocity.size()));
    if (!dynamic()) throw std::invalid_argument("initial velocities: a quasi-static simulation has none");
    if (!setup_.initial_velocity.allFinite()) throw std::invalid_argument("initial velocities: not finite");
    v_ = setup_.initial_velocity;
  }
  previous_ = x_;
  v_previous_ = v_;
  rest_volume_ = elastic_.rest_volumes().sum();
  if (!setup_.fibre_of_cell.empty() || !setup_.fibres.empty()) elastic_.set_fibres(setup_.fibre_of_cell, setup_.fibres);
  activate(time_);
}

void Simulation::activate(double t) {
  if (!setup_.fibre_strain) return;
  const std::vector<CellFibre>& fibres = elastic_.fibres();
  const bool first = alpha_.size() != fibres.size();  // every entry is set at the first call
  if (first) alpha_.assign(fibres.size(), 0.0);
  std::vector<double> alpha = alpha_;
  setup_.fibre_strain(t, alpha);
  if (alpha.size() != fibres.size())
    throw std::invalid_argument(fmt::format("muscles: {} active strains for {} fibre sets", alpha.size(), fibres.size()));
  for (std::size_t f = 0; f < fibres.size(); ++f)
    if (first || alpha[f] != alpha_[f]) {
      elastic_.set_active_strain(static_cast<int>(f), ActiveStrain::along(fibres[f].direction, alpha[f]));
      alpha_[f] = alpha[f];
    }
}

void Simulation::place_kinematic(Eigen::VectorXd& state, double t) const {
  Eigen::Matrix3Xd P;
  for (const KinematicSet& s : setup_.kinematic) {
    s.provider->targets(t, P);
    for (std::size_t k = 0; k < s.vertices.size(); ++k)
      for (int a = 0; a < 3; ++a)
        if (s.axes[a]) state[3 * s.vertices[k] + a] = P(a, static_cast<Eigen::Index>(k));
  }
}

std::vector<bool> Simulation::kinematic_vertices() const {
  std::vector<bool> out(elastic_.mesh().vertex_count(), false);
  for (const KinematicSet& s : setup_.kinematic)
    for (int v : s.vertices) out[v] = true;
  return out;
}

namespace {

/// Adds a solve's Newton counts and times to a sum over several solves.
void accumulate(NewtonReport& sum, const NewtonReport& r) {
  sum.iterations += r.iterations;
  sum.line_search_steps += r.line_search_steps;
  sum.line_search_expansions += r.line_search_expansions;
  sum.linear_iterations += r.linear_iterations;
  sum.factorizations += r.factorizations;
  sum.true_hessian_steps += r.true_hessian_steps;
  sum.truncated_steps += r.truncated_steps;
  sum.chord_steps += r.chord_steps;
  sum.residual = std::max(sum.residual, r.residual);
  sum.last_step = std::max(sum.last_step, r.last_step);
  sum.energy = r.energy;
  sum.assembly_seconds += r.assembly_seconds;
  sum.solve_seconds += r.solve_seconds;
  sum.residuals.insert(sum.residuals.end(), r.residuals.begin(), r.residuals.end());
}

using Frame = Eigen::Matrix<double, 3, 4>;  ///< a carrier's frame of one vertex: [linear part | origin]

/// x (3 #V) in each vertex's frame: y_v = A_v⁻¹ (x_v − o_v).
Eigen::VectorXd into_frames(const std::vector<Frame>& frames, const Eigen::VectorXd& x) {
  Eigen::VectorXd y(x.size());
  for (Eigen::Index v = 0; v < x.size() / 3; ++v) {
    const Frame& f = frames[static_cast<std::size_t>(v)];
    y.segment<3>(3 * v) = f.leftCols<3>().partialPivLu().solve(x.segment<3>(3 * v) - f.col(3));
  }
  return y;
}

/// Coordinates y (3 #V) in each vertex's frame back out of it: x_v = A_v y_v + o_v.
Eigen::VectorXd out_of_frames(const std::vector<Frame>& frames, const Eigen::VectorXd& y) {
  Eigen::VectorXd x(y.size());
  for (Eigen::Index v = 0; v < y.size() / 3; ++v) {
    const Frame& f = frames[static_cast<std::size_t>(v)];
    x.segment<3>(3 * v) = f.leftCols<3>() * y.segment<3>(3 * v) + f.col(3);
  }
  return x;
}

}  // namespace

bool Simulation::carried_check() const {
  if (dynamic() || !setup_.carrier) return false;
  return std::any_of(setup_.terms.begin(), setup_.terms.end(), [](const std::shared_ptr<Term>& t) { return t->moving(); });
}

bool Simulation::has_contact() const {
  return std::any_of(setup_.terms.begin(), setup_.terms.end(), [](const std::shared_ptr<Term>& t) { return t->reports_contact(); });
}

Eigen::VectorXd Simulation::carry(const Eigen::VectorXd& x, double from, double to) const {
  std::vector<Frame> at_from, at_to;
  setup_.carrier(from, at_from);
  setup_.carrier(to, at_to);
  return out_of_frames(at_to, into_frames(at_from, x));
}

double Simulation::clearance(double from, double to, double h) {
  if (setup_.terms.empty()) return 1.0;
  // The pins' jump to their targets at `to` (and, when dynamic, the free DOFs' inertial prediction: the
  // guess the solve starts from; with carried_check(), the free DOFs carried along: the guess's base).
  const bool carried = carried_check();
  Eigen::VectorXd moved = dynamic() ? stepper(h).predicted : carried ? carry(x_, from, to) : x_;
  place_kinematic(moved, to);
  const Eigen::VectorXd dx = moved - x_;
  double alpha = 1.0;
  for (const std::shared_ptr<Term>& term : setup_.terms)
    if (term->moving()) alpha = std::min(alpha, term->sweep(x_, dx, from, to));
  if (alpha < 1.0 || (setup_.kinematic.empty() && !carried)) return alpha;
  // The other contact terms: the pins' jump alone (the free DOFs' move is the guess's, bounded in solve()),
  // or with carried_check() the same carried move.
  Eigen::VectorXd jump = x_;
  place_kinematic(jump, to);
  jump -= x_;
  if (carried) jump = dx;
  if (jump.isZero(0.0)) return alpha;
  for (const std::shared_ptr<Term>& term : setup_.terms) term->at_time(to);
  for (const std::shared_ptr<Term>& term : setup_.terms)
    if (!term->moving()) alpha = std::min(alpha, term->max_step(x_, jump));
  return alpha;
}

/// A step split into more parts than this stops (a collider crawling along a surface in parts of ever smaller
/// size would otherwise run for hours).
constexpr int kMaxSplits = 200;

StepReport Simulation::step(double t, const NewtonOptions* newton) {
  StepReport r = step_halving(t, setup_.dt, newton, 0);
  if (!r.converged && !r.interrupted && r.halvings > 0)
    r.failure += fmt::format(" (the step was retried in halves {} time{}, down to dt / {})", r.halvings, r.halvings == 1 ? "" : "s",
                             1 << setup_.step_halvings);
  return r;
}

StepReport Simulation::step_halving(double t, double h, const NewtonOptions* newton, int level) {
  if (!dynamic() || level >= setup_.step_halvings || !(t > time_)) return step_split(t, h, newton);
  const SimulationState start = state();
  StepReport whole = step_split(t, h, newton);
  if (whole.converged || whole.interrupted) return whole;
  // Not converged: back to the start, and the step as two halves (each retried the same way). Should they
  // fail too, the state is the whole step's last iterate at t again (as without halving), not a part's.
  const SimulationState failed = state();
  restore(start);
  StepReport total;
  total.halvings = 1;
  total.splits = whole.splits;
  // The failed attempt's work counts; its residual, last step and energy are not the answer's.
  NewtonReport attempt = std::move(whole.newton);
  attempt.residual = attempt.last_step = 0.0;
  attempt.residuals.clear();
  accumulate(total.newton, attempt);
  const double mid = time_ + 0.5 * (t - time_);
  for (const double end : {mid, t}) {
    StepReport part = step_halving(end, 0.5 * h, newton, level + 1);
    accumulate(total.newton, part.newton);
    total.halvings += part.halvings;
    total.splits += part.splits;
    if (part.interrupted) {
      restore(start);
      part.newton = std::move(total.newton);
      return part;
    }
    if (!part.converged) {  // the failing part's report, with the sums of the whole step
      restore(failed);
      part.newton = std::move(total.newton);
      part.halvings = total.halvings;
      part.splits = total.splits;
      return part;
    }
  }
  total.substeps = 1;
  return total;
}

StepReport Simulation::step_split(double t, double h, const NewtonOptions* newton) {
  const double t0 = time_;
  if (!(t > t0) || clearance(t0, t, h) >= 1.0) return solve(t, h, newton);
  // Not clear: shorten the part to the fraction found clear (checked again: the poses between are not
  // linear) until it is, solve it, and go on from there.
  const SimulationState start = state();
  StepReport total;
  double from = t0;
  for (;;) {
    double to = t;
    const auto part_of = [&](double end) { return dynamic() ? h * (end - from) / (t - t0) : h; };
    for (double alpha = clearance(from, to, part_of(to)); alpha < 1.0; alpha = clearance(from, to, part_of(to))) {
      to = from + alpha * (to - from);
      ++total.splits;
      if (!(alpha > 0.0) || !((to - from) > 1e-6 * (t - t0)) || total.splits > kMaxSplits) {
        restore(start);
        total.converged = false;
        total.substeps = 1;
        total.failed_substep = 1;
        total.failed_time = t;
        total.failure = fmt::format("contact: a collider or pinned vertex cannot move from t = {:.9g} towards {:.9g} without reaching "
                                    "the surface (the step was split {} times): does a script drive the surface into a collider?",
                                    from, t, total.splits);
        return total;
      }
    }
    const StepReport r = solve(to, part_of(to), newton);
    accumulate(total.newton, r.newton);
    if (r.interrupted || !r.converged) {
      if (r.interrupted) restore(start);
      // The failing part's report, with the Newton sums and the splits of the whole step.
      NewtonReport sum = std::move(total.newton);
      const int splits = total.splits;
      total = r;
      total.newton = std::move(sum);
      total.splits = splits;
      return total;
    }
    if (to == t) break;
    from = to;
  }
  total.substeps = 1;
  return total;
}

Simulation::Stepper Simulation::stepper(double h, Stage stage) const {
  Stepper s;
  if (stage == Stage::trapezoid) {  // TR-BDF2's first stage over h = γ dt: η = h/2 (dynamics.hpp)
    s.anchor = x_ + 0.5 * h * v_;
    s.h_eff = 0.5 * h;
    s.predicted = x_ + h * v_;
    return s;
  }
  // Variable-step BDF2 with ω = h / h_{n−1}: a₀ = (1 + 2ω)/(1 + ω), a₁ = −(1 + ω), a₂ = ω²/(1 + ω). It is
  // zero-stable for ω < 1 + √2; a step more than twice the last (after a step split for contact) is made
  // by backward Euler instead.
  const double omega = h_previous_ > 0.0 ? h / h_previous_ : 0.0;
  // TR-BDF2's second stage is BDF2 through x_n (h_{n−1} = γ dt) and x_γ: ω = (1 − γ)/γ.
  if ((setup_.integrator == Integrator::bdf2 || stage == Stage::second) && h_previous_ > 0.0 && omega <= 2.0) {
    const double a0 = (1.0 + 2.0 * omega) / (1.0 + omega), a1 = -(1.0 + omega), a2 = omega * omega / (1.0 + omega);
    s.anchor = -(a1 * x_ + a2 * previous_) / a0;
    s.h_eff = h / a0;
    s.predicted = s.anchor - s.h_eff * (a1 * v_ + a2 * v_previous_) / a0;
  } else {
    s.anchor = x_;
    s.h_eff = h;
    s.predicted = x_ + h * v_;
  }
  return s;
}

Eigen::VectorXd Simulation::carried_guesses(double t, const Eigen::VectorXd& x_n, Eigen::VectorXd& guess, double& E) {
  // solve()'s extrapolations made in the carrier's frames (steps of equal length assumed, as there): the
  // states at t_n, t_n − Δ, t_n − 2Δ (Δ = t − t_n) taken into the frames of their times, extrapolated
  // there, and carried to t.
  const double delta = t - time_;
  std::vector<Frame> at_t, at_n;
  setup_.carrier(t, at_t);
  setup_.carrier(time_, at_n);
  auto consider = [&](Eigen::VectorXd candidate) {
    place_kinematic(candidate, t);
    const double Ec = problem_.energy(candidate);
    if (Ec < E || (!std::isfinite(E) && std::isfinite(Ec))) {
      guess = std::move(candidate);
      E = Ec;
    }
  };
  const Eigen::VectorXd y0 = into_frames(at_n, x_n);
  const Eigen::VectorXd x_n_carried = out_of_frames(at_t, y0);
  consider(x_n_carried);
  if (steps_ >= 1) {
    std::vector<Frame> at_1;
    setup_.carrier(time_ - delta, at_1);
    const Eigen::VectorXd y1 = into_frames(at_1, previous_);
    consider(out_of_frames(at_t, 2.0 * y0 - y1));
    if (setup_.extrapolation >= 2 && steps_ >= 2 && previous2_.size() == x_.size()) {
      std::vector<Frame> at_2;
      setup_.carrier(time_ - 2.0 * delta, at_2);
      consider(out_of_frames(at_t, 3.0 * (y0 - y1) + into_frames(at_2, previous2_)));
    }
  }
  return x_n_carried;
}

Eigen::VectorXd Simulation::start_force(double t_stage) {
  activate(time_);
  problem_.at_time(time_);
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(x_.size());
  elastic_.evaluate(x_, &gradient, nullptr, PsdProjection::none);
  bool lagged = false;
  for (const std::shared_ptr<Term>& term : setup_.terms) {
    if (term->lagged()) lagged = true;
    else term->evaluate(x_, &gradient, nullptr, PsdProjection::none);
  }
  if (!lagged) return -gradient;
  // Friction: its data taken at x_n as the stage's solve takes them (after at_time of the stage's end), its
  // force at x_n + (t_stage − t_n) v_n: what sliding at v_n meets. A function of x_n and v_n alone, so that a
  // resumed run or a retried step computes the same.
  problem_.at_time(t_stage);
  const Eigen::VectorXd slid = x_ + (t_stage - time_) * v_;
  for (const std::shared_ptr<Term>& term : setup_.terms)
    if (term->lagged()) {
      term->begin_step(x_, time_, t_stage);
      term->evaluate(slid, &gradient, nullptr, PsdProjection::none);
    }
  return -gradient;
}

StepReport Simulation::solve(double t, double h, const NewtonOptions* newton) {
  if (setup_.integrator != Integrator::tr_bdf2) return solve_stage(t, h, newton, Stage::whole);
  // TR-BDF2 with γ = 2 − √2 (docs/math.md §7.7): the trapezoidal rule to t_n + γ(t − t_n), then BDF2 through
  // x_n and x_γ to t. Each stage is a solve of its own; the step is one step to the caller.
  constexpr double gamma = 0.58578643762690495;  // 2 − √2
  const SimulationState start = state();
  const double t_n = time_;
  trapezoid_force_ = start_force(t_n + gamma * (t - t_n));
  if (!trapezoid_force_.allFinite()) {
    StepReport failed;
    failed.converged = false;
    failed.substeps = failed.failed_substep = 1;
    failed.failed_time = time_ = t;  // on the clock of the whole step, as below
    failed.failure = "TR-BDF2: the force at the step's start is not finite" + worst_element(elastic_.deformation(x_).min_J);
    return failed;
  }
  StepReport first = solve_stage(t_n + gamma * (t - t_n), gamma * h, newton, Stage::trapezoid);
  if (first.interrupted) return first;  // back at the start already
  if (!first.converged) {  // the failing stage's last iterate, on the clock of the whole step
    time_ = first.failed_time = t;
    h_previous_ = 0.0;
    first.failure = "TR-BDF2's first stage: " + first.failure;
    return first;
  }
  StepReport second = solve_stage(t, (1.0 - gamma) * h, newton, Stage::second);
  h_previous_ = 0.0;  // the next step starts from x and v alone
  if (!second.converged && !second.interrupted) second.failure = "TR-BDF2's second stage: " + second.failure;
  accumulate(first.newton, second.newton);
  second.newton = std::move(first.newton);
  if (second.interrupted) restore(start);
  return second;
}

StepReport Simulation::solve_stage(double t, double h, const NewtonOptions* newton, Stage stage) {
  StepReport report;
  report.substeps = 1;
  const Eigen::VectorXd x_n = x_, v_n = v_, previous_n = previous_, previous2_n = previous2_;
  // The guess: the inertial prediction (dynamic), a linear extrapolation from the last two solutions, or
  // for the first quasi-static step the setup's (the current state by default).
  Stepper stepping;
  Eigen::VectorXd guess;
  if (dynamic()) {
    stepping = stepper(h, stage);
    guess = stepping.predicted;
  }
  else if (steps_ >= 1) guess = 2.0 * x_ - previous_;
  else guess = setup_.first_guess ? setup_.first_guess(x_, t) : x_;
  place_kinematic(guess, t);
  activate(t);
  problem_.at_time(t);
  for (const std::shared_ptr<Term>& term : setup_.terms) term->begin_step(x_n, time_, t);  // lagged data (friction)
  // The inertia term's step is ĥ for this solve only (a part of a split step, or BDF2's h/a₀).
  struct RestoreDt {
    TimeStepTerm& term;
    double dt;
    ~RestoreDt() { term.set_dt(dt); }
  } restore_dt{inertia_, inertia_.terms().dt};
  if (stage == Stage::trapezoid) {
    inertia_.set_dt(stepping.h_eff);
    inertia_.begin_trapezoid(x_n, v_n, trapezoid_force_);
  } else if (dynamic()) {
    inertia_.set_dt(stepping.h_eff);
    inertia_.begin_step(x_n, stepping.anchor, stepping.predicted);
  } else {
    inertia_.begin_step(x_n, v_);
  }
  double E = problem_.energy(guess);
  if (!dynamic() && setup_.extrapolation >= 2 && steps_ >= 2 && previous2_.size() == x_.size()) {
    // The quadratic extrapolation is closer along a smooth motion; at a kink of a keyframed one (a joint
    // that stops or turns) the linear one can be: the lower energy decides.
    Eigen::VectorXd quadratic = 3.0 * (x_ - previous_) + previous2_;
    place_kinematic(quadratic, t);
    const double Eq = problem_.energy(quadratic);
    if (Eq < E || (!std::isfinite(E) && std::isfinite(Eq))) {
      guess = std::move(quadratic);
      E = Eq;
    }
  }
  // x_n carried to t by the carrier's frames (quasi-static runs with a carrier), its extrapolations considered
  const Eigen::VectorXd x_n_carried = !dynamic() && setup_.carrier ? carried_guesses(t, x_n, guess, E) : Eigen::VectorXd();
  {
    // Contact terms bound the move from x_n (its kinematic DOFs already at t) to the guess by continuous
    // collision detection, so that the guess never jumps through a contact (a term without a bound, as
    // every one but contact, says 1: the guess is then unchanged).
    // With carried_check() the base is x_n carried to t, which step() checked instead.
    Eigen::VectorXd base = carried_check() ? x_n_carried : x_n;
    for (Eigen::Index d = 0; d < base.size(); ++d)
      if (!dofs_.is_free(d)) base[d] = guess[d];  // the kinematic DOFs as placed (providers asked once a step)
    const Eigen::VectorXd dx = dofs_.gather_free(guess) - dofs_.gather_free(base);
    // A moving collider's bound is its sweep from (x_n, its pose at the last time) to (the guess, its pose
    // at t), which step() found clear for backward Euler's prediction (base itself may be inside it at t);
    // quasi-statically base is clear of it (step() checked the pins' jump, or the carried move) and its
    // max_step applies.
    double alpha = 1.0;
    const Eigen::VectorXd dx_full = dofs_.expand(dx);
    for (const std::shared_ptr<Term>& term : setup_.terms)
      alpha = std::min(alpha, dynamic() && term->moving() ? term->sweep(x_n, guess - x_n, time_, t) : term->max_step(base, dx_full));
    if (alpha < 1.0) {
      guess = base + alpha * dofs_.expand(dx);
      E = problem_.energy(guess);
    }
  }
  if (!std::isfinite(E)) {  // the prediction leaves an energy's domain
    guess = setup_.fallback_guess ? setup_.fallback_guess(x_n, t) : x_n;
    place_kinematic(guess, t);
  }
  if (!dynamic() && setup_.extrapolation >= 2 && steps_ >= 1) previous2_ = previous_;
  previous_ = x_n;
  x_ = guess;
  report.newton = newton_solve(problem_, x_, *solver_, newton ? *newton : setup_.newton);
  const NewtonReport& r = report.newton;
  if (r.interrupted) {  // abandon the step: back to where it started
    x_ = x_n;
    previous_ = previous_n;
    previous2_ = previous2_n;
    report.interrupted = true;
    report.converged = false;
    report.failure = r.failure;
    return report;
  }
  if (dynamic()) {
    v_ = (x_ - stepping.anchor) / stepping.h_eff;
    v_previous_ = v_n;
    h_previous_ = h;
  }
  time_ = t;
  if (!r.converged) {
    report.converged = false;
    report.failed_substep = 1;
    report.failed_time = t;
    report.failure = r.failure + worst_element(elastic_.deformation(x_.allFinite() ? x_ : x_n).min_J);
    if (!x_.allFinite()) {  // never keep a non-finite state (nor the velocity made from it)
      x_ = x_n;
      v_ = v_n;
    }
    return report;
  }
  if (stage != Stage::trapezoid) ++steps_;  // a TR-BDF2 step counts once
  return report;
}

StepReport Simulation::advance(double t_start, double h, int substeps, const NewtonOptions* newton,
                               const std::function<void(int)>& on_substep) {
  const SimulationState start = state();
  StepReport frame;
  for (int sub = 1; sub <= substeps; ++sub) {
    const double t = t_start + sub * h;
    if (on_substep) on_substep(sub);
    const StepReport r = step(t, newton);
    if (r.interrupted) {
      restore(start);
      frame.interrupted = true;
      frame.converged = false;
      frame.failure = r.failure;
      return frame;
    }
    frame.substeps = sub;
    frame.splits += r.splits;
    frame.halvings += r.halvings;
    accumulate(frame.newton, r.newton);
    if (!r.converged) {
      frame.converged = false;
      frame.failed_substep = sub;
      frame.failed_time = t;
      frame.failure = r.failure;
      return frame;
    }
  }
  return frame;
}

SimulationState Simulation::state() const {
  if (setup_.integrator == Integrator::bdf2 && h_previous_ > 0.0) {
    const Eigen::Index n = x_.size();
    Eigen::VectorXd aux(3 * n + 1);
    aux << v_, previous_, v_previous_, h_previous_;
    return {.x = x_, .aux = std::move(aux), .time = time_, .steps = steps_};
  }
  if (dynamic()) return {.x = x_, .aux = v_, .time = time_, .steps = steps_};
  if (setup_.extrapolation < 2 || previous2_.size() != x_.size()) return {.x = x_, .aux = previous_, .time = time_, .steps = steps_};
  Eigen::VectorXd both(2 * x_.size());
  both << previous_, previous2_;
  return {.x = x_, .aux = std::move(both), .time = time_, .steps = steps_};
}

void Simulation::restore(const SimulationState& s) {
  const Eigen::Index n = x_.size();
  const bool two = !dynamic() && setup_.extrapolation >= 2 && s.aux.size() == 2 * n;
  const bool history = setup_.integrator == Integrator::bdf2 && s.aux.size() == 3 * n + 1;
  if (s.x.size() != n || (s.aux.size() != n && !two && !history) || (history && !(s.aux[3 * n] > 0.0)))
    throw std::invalid_argument(fmt::format("a saved state of {} and {} numbers for a mesh of {} DOFs", s.x.size(), s.aux.size(), n));
  x_ = s.x;
  if (dynamic()) {
    v_ = s.aux.head(n);
    previous_ = history ? Eigen::VectorXd(s.aux.segment(n, n)) : x_;
    v_previous_ = history ? Eigen::VectorXd(s.aux.segment(2 * n, n)) : v_;
    h_previous_ = history ? s.aux[3 * n] : 0.0;
  } else {
    previous_ = s.aux.head(n);
  }
  if (two) previous2_ = s.aux.tail(n);
  else previous2_.resize(0);
  time_ = s.time;
  steps_ = s.steps;
  activate(time_);
}

}  // namespace snh
