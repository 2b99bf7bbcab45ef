#pragma once
// What Newton minimises (docs/design.md): a sum of energy terms over the free DOFs of a DofMap, the
// kinematic DOFs held at their values in x. The problem owns the Hessian layout over the free DOFs: the
// union of the terms' stencils, built by the first evaluation that asks for a Hessian and rebuilt (each
// term's bind() called again) when a term whose stencil varies couples vertices the layout does not, for what
// those terms may couple soon (Term::stencil_ahead), so that one rebuild serves many iterates; fixed
// stencils (elasticity) are asked once.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/dof_map.hpp"
#include "snh/fem/hessian_layout.hpp"
#include "snh/fem/term.hpp"

namespace snh {

/// A free-DOF Hessian with the id of the layout its pattern came from.
struct HessianMatrix {
  SparseLower matrix;
  std::uint64_t layout = 0;
};

class Problem {
 public:
  explicit Problem(DofMap dofs) : dofs_(std::move(dofs)) {}
  /// Adds a term (not owned: it must outlive the problem). Terms are summed in the order added.
  void add(Term& term);

  [[nodiscard]] const DofMap& dofs() const { return dofs_; }
  [[nodiscard]] const std::vector<Term*>& terms() const { return terms_; }

  /// Σ terms' energies at x (3 #V); +∞ as soon as one is.
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const;
  /// The energy; the gradient on the free DOFs (resized to free_count()); and when hessian is not null
  /// the Hessian on the free DOFs, its pattern replaced first if it is not the current layout's.
  /// Returns +∞ (gradient and Hessian not meaningful) where a term is undefined.
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, HessianMatrix* hessian, PsdProjection projection);
  /// The Hessian alone at x (no gradient: Newton has it from the line search), as evaluate() makes it.
  void hessian(const Eigen::VectorXd& x, HessianMatrix& hessian, PsdProjection projection);
  /// The smallest max_step over the terms for the step dx on the free DOFs (free_count()).
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx_free) const;
  /// Tells every term that Newton accepted x.
  void on_accepted(const Eigen::VectorXd& x);
  /// Tells every term the time of the next solve.
  void at_time(double t);
  /// Layouts built so far (1 after the first evaluation; more when varying stencils grew it).
  [[nodiscard]] int layouts_built() const { return layouts_built_; }
  /// The matrix newton_solve() assembles into, kept from one solve to the next: while the layout stays, a
  /// solve refills its values rather than copying the layout's whole pattern into new memory (80 MB and
  /// 12 ms per solve at Figure 1's size).
  [[nodiscard]] HessianMatrix& newton_matrix() { return newton_matrix_; }

 private:
  /// Builds the layout if there is none, or if a varying stencil at x is not covered.
  void update_layout(const Eigen::VectorXd& x);
  /// Σ terms' evaluate() into `gradient` (null: none) and `hessian` (null: none).
  double sum_terms(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, HessianMatrix* hessian, PsdProjection projection);
  DofMap dofs_;
  std::vector<Term*> terms_;
  std::vector<Stencil> fixed_, varying_;  ///< per term (empty where not of that kind)
  HessianLayout layout_;
  bool have_layout_ = false;
  int layouts_built_ = 0;
  HessianMatrix newton_matrix_;
};

}  // namespace snh
