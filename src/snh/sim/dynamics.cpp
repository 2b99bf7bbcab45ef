#include "snh/sim/dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <variant>

namespace snh {

Eigen::VectorXd lumped_mass(const ElasticSystem& system, double density) {
  if (!(density > 0.0) || !std::isfinite(density)) throw std::invalid_argument("density must be a finite number > 0");
  const VolumeMesh& mesh = system.mesh();
  const Eigen::VectorXd volume = rest_volumes(system.rest());
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(3 * mesh.vertex_count());
  const int n = nodes_per_cell(mesh.type);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int a = 0; a < n; ++a) mass.segment<3>(3 * mesh.cells(a, c)).array() += density * volume[c] / n;
  return mass;
}

TimeStepPotential::TimeStepPotential(const ElasticSystem& elastic, Eigen::VectorXd mass, StepTerms terms)
    : elastic_(elastic), mass_(std::move(mass)), terms_(terms) {
  if (mass_.size() != 3 * elastic.mesh().vertex_count()) throw std::invalid_argument("mass: one entry per DOF");
  if (!(terms_.dt >= 0.0) || !std::isfinite(terms_.dt)) throw std::invalid_argument("time step must be >= 0");
  if (!(terms_.mass_damping >= 0.0) || !(terms_.stiffness_damping >= 0.0))
    throw std::invalid_argument("damping coefficients must be >= 0");
  gravity_.resize(mass_.size());
  for (Eigen::Index d = 0; d < gravity_.size(); ++d) gravity_[d] = terms_.gravity[d % 3];
  const SparseLower& p = elastic.pattern();
  diagonal_.resize(p.cols());
  for (Eigen::Index c = 0; c < p.cols(); ++c) diagonal_[c] = p.outerIndexPtr()[c];  // columns start at the diagonal
}

void TimeStepPotential::begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n) {
  x_n_ = x_n;
  predicted_ = x_n + terms_.dt * v_n;
  if (terms_.dt > 0.0 && terms_.stiffness_damping > 0.0) {
    Eigen::VectorXd unused;
    K_n_ = elastic_.pattern();
    elastic_.evaluate(x_n, unused, &K_n_, PsdProjection::clamp);
  }
}

double TimeStepPotential::extra_terms(const Eigen::VectorXd& x, Eigen::VectorXd* gradient) const {
  const std::vector<int>& free = elastic_.free_index();
  const double h = terms_.dt;
  double value = 0.0;
  Eigen::VectorXd delta;  // x − x_n on the free DOFs, for stiffness damping
  const bool stiffness = h > 0.0 && terms_.stiffness_damping > 0.0;
  if (stiffness) delta.setZero(elastic_.free_count());
  for (std::size_t d = 0; d < free.size(); ++d) {
    const int f = free[d];
    if (f < 0) continue;
    const Eigen::Index i = static_cast<Eigen::Index>(d);
    const double m = mass_[i];
    double g = -m * gravity_[i];
    value -= m * gravity_[i] * x[i];
    if (h > 0.0) {
      const double inertial = x[i] - predicted_[i], moved = x[i] - x_n_[i];
      value += m / (2 * h * h) * inertial * inertial + terms_.mass_damping * m / (2 * h) * moved * moved;
      g += m / (h * h) * inertial + terms_.mass_damping * m / h * moved;
      if (stiffness) delta[f] = moved;
    }
    if (gradient) (*gradient)[f] += g;
  }
  if (stiffness) {
    const Eigen::VectorXd Kd = K_n_.selfadjointView<Eigen::Lower>() * delta;
    const double beta_h = terms_.stiffness_damping / h;
    value += 0.5 * beta_h * delta.dot(Kd);
    if (gradient) *gradient += beta_h * Kd;
  }
  return value;
}

double TimeStepPotential::energy(const Eigen::VectorXd& x) const {
  const double elastic = elastic_.energy(x);
  if (!std::isfinite(elastic)) return elastic;
  return elastic + extra_terms(x, nullptr);
}

double TimeStepPotential::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, SparseLower* hessian,
                                   PsdProjection projection) const {
  const double elastic = elastic_.evaluate(x, gradient, hessian, projection);
  if (!std::isfinite(elastic)) return elastic;
  const double value = elastic + extra_terms(x, &gradient);
  const double h = terms_.dt;
  if (hessian && h > 0.0) {
    const std::vector<int>& free = elastic_.free_index();
    double* values = hessian->valuePtr();
    for (std::size_t d = 0; d < free.size(); ++d)
      if (free[d] >= 0)
        values[diagonal_[free[d]]] += mass_[static_cast<Eigen::Index>(d)] * (1.0 / (h * h) + terms_.mass_damping / h);
    if (terms_.stiffness_damping > 0.0) {
      const double beta_h = terms_.stiffness_damping / h;
      for (Eigen::Index k = 0; k < K_n_.nonZeros(); ++k) values[k] += beta_h * K_n_.valuePtr()[k];
    }
  }
  return value;
}

double TimeStepPotential::kinetic_energy(const Eigen::VectorXd& v) const {
  return 0.5 * (mass_.array() * v.array().square()).sum();
}

double TimeStepPotential::gravity_energy(const Eigen::VectorXd& x) const {
  return -(mass_.array() * gravity_.array() * x.array()).sum();
}

}  // namespace snh
