#pragma once
// Time stepping (DESIGN.md sim/): implicit (backward) Euler on positions as the minimisation of an
// incremental potential, and quasi-static steps with external forces, both solved by projected Newton.
//
// Backward Euler with step h, lumped masses m, gravity g and Rayleigh-style damping D = αM + βK:
//   x_{n+1} = argmin  Ψ(x) + Σ m/(2h²) |x − x̃|² + α/(2h) Σ m |x − x_n|² + β/(2h) Δᵀ K_n Δ − Σ m g·x,
//   x̃ = x_n + h v_n,  Δ = x − x_n,  v_{n+1} = (x_{n+1} − x_n)/h,
// where K_n is the PSD-projected elastic Hessian at x_n on the free DOFs (so β damps the free DOFs'
// velocities relative to each other and to the pins). Its stationarity condition is exactly backward
// Euler: M(x − x̃)/h² = f_elastic + f_gravity − D v_{n+1}. Quasi-static steps (h = 0) minimise Ψ − Σ m g·x.
// Sums run over the free DOFs; pinned DOFs are set before each step.
#include <Eigen/Core>

#include "snh/fem/elastic_system.hpp"
#include "snh/fem/objective.hpp"

namespace snh {

/// Lumped mass per DOF (3 #V, the same for x, y and z of a vertex): density × each cell's rest volume,
/// shared equally among the cell's nodes. Σ over a vertex's x entries = density × total rest volume.
[[nodiscard]] Eigen::VectorXd lumped_mass(const ElasticSystem& system, double density);

struct StepTerms {
  double dt = 0.0;                ///< time step h; 0 for a quasi-static step (no inertia or damping)
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  double mass_damping = 0.0;      ///< α (1/time)
  double stiffness_damping = 0.0; ///< β (time)
};

/// The incremental potential of one step. Call begin_step() before minimising each step.
class TimeStepPotential final : public Objective {
 public:
  /// mass: lumped_mass(elastic, density). The elastic system must outlive this object.
  TimeStepPotential(const ElasticSystem& elastic, Eigen::VectorXd mass, StepTerms terms);

  /// The state at the start of the step (full DOF vectors); assembles K_n when β > 0.
  void begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n);

  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, SparseLower* hessian,
                  PsdProjection projection) const override;
  [[nodiscard]] const SparseLower& pattern() const override { return elastic_.pattern(); }
  void scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const override {
    elastic_.scatter_add_free(free, scale, full);
  }

  [[nodiscard]] const StepTerms& terms() const { return terms_; }
  [[nodiscard]] const Eigen::VectorXd& mass() const { return mass_; }
  /// ½ Σ m v² over all DOFs.
  [[nodiscard]] double kinetic_energy(const Eigen::VectorXd& v) const;
  /// −Σ m g·x over all DOFs (0 at x = 0).
  [[nodiscard]] double gravity_energy(const Eigen::VectorXd& x) const;

 private:
  /// The non-elastic terms: value, and their gradient added to `gradient` (free DOFs).
  double extra_terms(const Eigen::VectorXd& x, Eigen::VectorXd* gradient) const;
  const ElasticSystem& elastic_;
  Eigen::VectorXd mass_;        ///< per DOF
  Eigen::VectorXd gravity_;     ///< per DOF: g component of each DOF's axis
  StepTerms terms_;
  Eigen::VectorXd x_n_, predicted_;
  SparseLower K_n_;             ///< β > 0: projected elastic Hessian at x_n
  std::vector<int> diagonal_;   ///< value index of each free DOF's diagonal entry in pattern()
};

}  // namespace snh
