#pragma once
// Time stepping (docs/design.md): implicit (backward) Euler on positions as the minimisation of an
// incremental potential, and quasi-static steps with external forces, both solved by projected Newton.
//
// Backward Euler with step h, lumped masses m, gravity g and Rayleigh-style damping D = αM + βK:
//   x_{n+1} = argmin  Ψ(x) + Σ m/(2h²) |x − x̃|² + α/(2h) Σ m |x − x_n|² + β/(2h) Δᵀ K_n Δ − Σ m g·x,
//   x̃ = x_n + h v_n,  Δ = x − x_n,  v_{n+1} = (x_{n+1} − x_n)/h,
// where K_n is the PSD-projected elastic Hessian at x_n over every DOF, free and kinematic: its force on
// the free DOFs is −β/h (K_n Δ)_f, which vanishes for a rigid translation, so a body carried by moving
// pins or bones is not damped towards standing still in the world. Its stationarity condition is exactly
// backward Euler: M(x − x̃)/h² = f_elastic + f_gravity − D v_{n+1}. Quasi-static steps (h = 0) minimise
// Ψ − Σ m g·x.
//
// BDF2 is the same minimisation with x_n replaced by an anchor x̂ and h by h/a₀: with the coefficients
// a₀ x_{n+1} + a₁ x_n + a₂ x_{n−1} = h v_{n+1} (a₀ = 3/2, a₁ = −2, a₂ = ½ for equal steps), x̂ = −(a₁ x_n +
// a₂ x_{n−1})/a₀, v̂ = −(a₁ v_n + a₂ v_{n−1})/a₀ and ĥ = h/a₀, the step is x̃ = x̂ + ĥ v̂, Δ = x − x̂,
// v_{n+1} = (x_{n+1} − x̂)/ĥ, and K_n is still taken at x_n (docs/math.md §7.5). The inertia, mass-damping and gravity sums run over the free DOFs (on kinematic DOFs they
// are constants of the step); kinematic DOFs are set before each step.
//
// TR-BDF2's first stage (docs/math.md §7.7) is the trapezoidal rule over γh, x_γ = x_n + η(v_n + v_γ),
// M(v_γ − v_n) = η(f_n + f_γ) with η = γh/2: the same minimisation over η with the inertia's target
// x̃ = x_n + 2η v_n + η² M⁻¹ f_n (f_n the whole force at x_n, damping at v_n included) and the damping of
// the motion from x_n + η v_n (its force is then −D v_γ). Its second stage is BDF2 through x_n and x_γ.
#include <Eigen/Core>

#include "snh/fem/dof_map.hpp"
#include "snh/fem/elastic_term.hpp"
#include "snh/fem/term.hpp"

namespace snh {

/// Lumped mass per DOF (3 #V, the same for x, y and z of a vertex): density × each cell's rest volume
/// (its quadrature weights, scaled where the elastic term scales them), shared equally among the cell's
/// nodes. Σ over a vertex's x entries = density × total rest volume.
[[nodiscard]] Eigen::VectorXd lumped_mass(const ElasticTerm& elastic, double density);

struct StepTerms {
  double dt = 0.0;                ///< time step h; 0 for a quasi-static step (no inertia or damping)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double mass_damping = 0.0;      ///< α (1/time)
  double stiffness_damping = 0.0; ///< β (time)
};

/// The non-elastic part of a step's incremental potential: inertia, mass damping and gravity, and
/// stiffness damping. Call begin_step() before minimising each step.
class TimeStepTerm final : public Term {
 public:
  /// elastic  the elastic term (must outlive this one; K_n is its Hessian)
  /// dofs     the problem's free and kinematic DOFs
  /// mass     lumped_mass(elastic, density)
  TimeStepTerm(const ElasticTerm& elastic, const DofMap& dofs, Eigen::VectorXd mass, StepTerms terms);

  /// The state at the start of a backward Euler step (full DOF vectors); assembles K_n when β > 0 and h > 0.
  void begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n);
  /// The general form (BDF2): K_n at x_n, inertia towards `predicted`, damping of the motion from `anchor`
  /// over the current dt (set_dt: ĥ). begin_step(x_n, v_n) is begin_step(x_n, x_n, x_n + dt v_n).
  void begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& anchor, const Eigen::VectorXd& predicted);
  /// TR-BDF2's trapezoidal stage over 2η (set_dt(η) first): K_n at x_n, inertia towards x_n + 2η v_n + η² M⁻¹ f,
  /// damping of the motion from x_n + η v_n. `force` is the force at x_n of every other term (−their gradient,
  /// every DOF); gravity and the damping force at v_n are added here. A free DOF without mass keeps x_n + 2η v_n.
  void begin_trapezoid(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n, const Eigen::VectorXd& force);

  [[nodiscard]] std::string_view name() const override { return "inertia"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  /// Stiffness damping couples what elasticity couples: the elastic term's stencil covers it.
  void bind(const HessianLayout& layout) override;

  [[nodiscard]] const StepTerms& terms() const { return terms_; }
  /// A different time step h > 0 from the next begin_step on (a step split in time); the caller sets it back.
  void set_dt(double h) { terms_.dt = h; }
  [[nodiscard]] const Eigen::VectorXd& mass() const { return mass_; }
  /// ½ Σ m v² over all DOFs.
  [[nodiscard]] double kinetic_energy(const Eigen::VectorXd& v) const;
  /// −Σ m g·x over all DOFs (0 at x = 0).
  [[nodiscard]] double gravity_energy(const Eigen::VectorXd& x) const;

 private:
  [[nodiscard]] bool damps_stiffness() const { return terms_.dt > 0.0 && terms_.stiffness_damping > 0.0; }
  /// K_n u for u on every DOF, in the damping numbering (free DOFs first); `numbered` receives u so numbered.
  [[nodiscard]] Eigen::VectorXd stiffness_times(const Eigen::VectorXd& u, Eigen::VectorXd& numbered) const;
  const ElasticTerm& elastic_;
  const DofMap& dofs_;
  Eigen::VectorXd mass_;        ///< per DOF
  Eigen::VectorXd gravity_;     ///< per DOF: g component of each DOF's axis
  StepTerms terms_;
  Eigen::VectorXd anchor_, predicted_;  ///< x_n (BDF2: x̂) and x̃
  // Stiffness damping (β > 0): K_n over every DOF, numbered free DOFs first (as the problem numbers them)
  // and kinematic DOFs after, with the elastic term's scatter map into it.
  HessianLayout damping_layout_;
  std::vector<int> damping_scatter_;
  SparseLower K_n_;
  std::vector<int> diagonal_;   ///< value index of each free DOF's diagonal entry in the bound layout
  std::vector<int> damping_map_;  ///< per value of the bound layout, the K_n value at the same (row, col); −1 if none
};

}  // namespace snh
