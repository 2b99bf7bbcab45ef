#pragma once
// What Newton minimises (DESIGN.md solve/): an energy of the full DOF vector x (3 #V) whose gradient and
// Hessian are taken on the free DOFs only, in a fixed sparse pattern. ElasticSystem is one (quasi-static
// equilibrium); sim/dynamics.hpp's TimeStepPotential adds inertia, damping and gravity to it.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "snh/material/psd_projection.hpp"

namespace snh {

/// The lower triangle of a symmetric free-DOF matrix, column-major (the form CHOLMOD takes); every
/// column starts with its diagonal entry.
using SparseLower = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

class Objective {
 public:
  virtual ~Objective() = default;
  /// The energy at x; +∞ where x is outside its domain.
  [[nodiscard]] virtual double energy(const Eigen::VectorXd& x) const = 0;
  /// Energy, gradient on the free DOFs and (optionally) the Hessian on the free DOFs (elastic terms
  /// PSD-projected per element with `projection`), overwritten in the pattern() layout.
  virtual double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, SparseLower* hessian,
                          PsdProjection projection) const = 0;
  /// An empty matrix with the fixed sparsity pattern of the free-DOF Hessian.
  [[nodiscard]] virtual const SparseLower& pattern() const = 0;
  /// full[d] += scale · free[free index of d] for every free DOF d.
  virtual void scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const = 0;
};

}  // namespace snh
