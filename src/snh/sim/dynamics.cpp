#include "snh/sim/dynamics.hpp"

#include <cmath>
#include <stdexcept>
#include <variant>

namespace snh {

Eigen::VectorXd lumped_mass(const ElasticTerm& elastic, double density) {
  if (!(density > 0.0) || !std::isfinite(density)) throw std::invalid_argument("density must be a finite number > 0");
  const VolumeMesh& mesh = elastic.mesh();
  const Eigen::VectorXd volume = elastic.rest_volumes();
  Eigen::VectorXd mass = Eigen::VectorXd::Zero(3 * mesh.vertex_count());
  const int n = nodes_per_cell(mesh.type);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int a = 0; a < n; ++a) mass.segment<3>(3 * mesh.cells(a, c)).array() += density * volume[c] / n;
  return mass;
}

TimeStepTerm::TimeStepTerm(const ElasticTerm& elastic, const DofMap& dofs, Eigen::VectorXd mass, StepTerms terms)
    : elastic_(elastic), dofs_(dofs), mass_(std::move(mass)), terms_(terms) {
  if (mass_.size() != 3 * elastic.mesh().vertex_count() || dofs.dofs() != mass_.size())
    throw std::invalid_argument("mass: one entry per DOF");
  if (!(terms_.dt >= 0.0) || !std::isfinite(terms_.dt)) throw std::invalid_argument("time step must be >= 0");
  if (!(terms_.mass_damping >= 0.0) || !(terms_.stiffness_damping >= 0.0))
    throw std::invalid_argument("damping coefficients must be >= 0");
  gravity_.resize(mass_.size());
  for (Eigen::Index d = 0; d < gravity_.size(); ++d) gravity_[d] = terms_.gravity[d % 3];
  if (damps_stiffness()) {
    std::vector<int> numbering = dofs.free_index();
    int next = static_cast<int>(dofs.free_count());
    for (int& n : numbering)
      if (n < 0) n = next++;
    Stencil cells;
    elastic.stencil(Eigen::VectorXd(), cells);
    damping_layout_ = HessianLayout(std::move(numbering), next, {&cells});
    damping_scatter_ = elastic.scatter_map(damping_layout_);
  }
}

void TimeStepTerm::bind(const HessianLayout& layout) {
  const SparseLower& p = layout.pattern();
  diagonal_.resize(p.cols());
  for (Eigen::Index c = 0; c < p.cols(); ++c) diagonal_[c] = p.outerIndexPtr()[c];  // columns start at the diagonal
  damping_map_.clear();
  if (!damps_stiffness()) return;
  // Free DOFs have the same number in both layouts.
  damping_map_.assign(p.nonZeros(), -1);
  for (Eigen::Index c = 0; c < p.cols(); ++c)
    for (int k = p.outerIndexPtr()[c]; k < p.outerIndexPtr()[c + 1]; ++k)
      damping_map_[k] = damping_layout_.entry(p.innerIndexPtr()[k], static_cast<int>(c));
}

void TimeStepTerm::begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n) {
  begin_step(x_n, x_n, x_n + terms_.dt * v_n);
}

void TimeStepTerm::begin_step(const Eigen::VectorXd& x_n, const Eigen::VectorXd& anchor, const Eigen::VectorXd& predicted) {
  if (anchor.size() != x_n.size() || predicted.size() != x_n.size()) throw std::invalid_argument("time-step term: sizes differ");
  anchor_ = anchor;
  predicted_ = predicted;
  if (damps_stiffness()) {
    K_n_ = damping_layout_.pattern();
    elastic_.add_hessian(x_n, damping_scatter_, K_n_.valuePtr(), PsdProjection::clamp);
  }
}

void TimeStepTerm::begin_trapezoid(const Eigen::VectorXd& x_n, const Eigen::VectorXd& v_n, const Eigen::VectorXd& force) {
  if (v_n.size() != x_n.size() || force.size() != x_n.size()) throw std::invalid_argument("time-step term: sizes differ");
  const double eta = terms_.dt;
  begin_step(x_n, x_n + eta * v_n, x_n + 2.0 * eta * v_n);
  Eigen::VectorXd Kv, numbered;
  if (damps_stiffness()) Kv = stiffness_times(v_n, numbered);
  const std::vector<int>& num = damping_layout_.numbering();
  const std::vector<int>& free = dofs_.free_index();
  for (std::size_t d = 0; d < free.size(); ++d) {
    const Eigen::Index i = static_cast<Eigen::Index>(d);
    const double m = mass_[i];
    if (free[d] < 0 || !(m > 0.0)) continue;
    double f = force[i] + m * (gravity_[i] - terms_.mass_damping * v_n[i]);
    if (damps_stiffness()) f -= terms_.stiffness_damping * Kv[num[d]];
    predicted_[i] += eta * eta * f / m;
  }
}

Eigen::VectorXd TimeStepTerm::stiffness_times(const Eigen::VectorXd& u, Eigen::VectorXd& numbered) const {
  const std::vector<int>& num = damping_layout_.numbering();
  numbered.resize(u.size());
  for (std::size_t d = 0; d < num.size(); ++d) numbered[num[d]] = u[static_cast<Eigen::Index>(d)];
  return K_n_.selfadjointView<Eigen::Lower>() * numbered;
}

double TimeStepTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                              PsdProjection) const {
  const std::vector<int>& free = dofs_.free_index();
  const double h = terms_.dt;
  if (anchor_.size() != x.size()) throw std::logic_error("time-step term: evaluated before begin_step()");
  double value = 0.0;
  for (std::size_t d = 0; d < free.size(); ++d) {
    if (free[d] < 0) continue;
    const Eigen::Index i = static_cast<Eigen::Index>(d);
    const double m = mass_[i];
    double g = -m * gravity_[i];
    value -= m * gravity_[i] * x[i];
    if (h > 0.0) {
      const double inertial = x[i] - predicted_[i], moved = x[i] - anchor_[i];
      value += m / (2 * h * h) * inertial * inertial + terms_.mass_damping * m / (2 * h) * moved * moved;
      g += m / (h * h) * inertial + terms_.mass_damping * m / h * moved;
    }
    if (gradient) (*gradient)[i] += g;
  }
  if (damps_stiffness()) {
    // Δ = x − x_n over every DOF in the damping numbering (free DOFs first), K_n Δ, and
    // ½ β/h Δᵀ K_n Δ summed as its free part plus its kinematic part.
    const std::vector<int>& num = damping_layout_.numbering();
    Eigen::VectorXd delta;
    const Eigen::VectorXd Kd = stiffness_times(x - anchor_, delta);
    const Eigen::Index nf = dofs_.free_count(), nk = x.size() - nf;
    const double beta_h = terms_.stiffness_damping / h;
    value += 0.5 * beta_h * (delta.head(nf).dot(Kd.head(nf)) + delta.tail(nk).dot(Kd.tail(nk)));
    if (gradient)
      for (std::size_t d = 0; d < num.size(); ++d) (*gradient)[static_cast<Eigen::Index>(d)] += beta_h * Kd[num[d]];
  }
  if (hessian && h > 0.0) {
    double* values = hessian->values();
    for (std::size_t d = 0; d < free.size(); ++d)
      if (free[d] >= 0)
        values[diagonal_[free[d]]] += mass_[static_cast<Eigen::Index>(d)] * (1.0 / (h * h) + terms_.mass_damping / h);
    if (damps_stiffness()) {
      const double beta_h = terms_.stiffness_damping / h;
      for (std::size_t k = 0; k < damping_map_.size(); ++k)
        if (damping_map_[k] >= 0) values[k] += beta_h * K_n_.valuePtr()[damping_map_[k]];
    }
  }
  return value;
}

double TimeStepTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double TimeStepTerm::kinetic_energy(const Eigen::VectorXd& v) const {
  return 0.5 * (mass_.array() * v.array().square()).sum();
}

double TimeStepTerm::gravity_energy(const Eigen::VectorXd& x) const {
  return -(mass_.array() * gravity_.array() * x.array()).sum();
}

}  // namespace snh
