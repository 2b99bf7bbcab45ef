#pragma once
// An energy term of the problem Newton minimises (docs/design.md): elasticity, inertia and damping,
// attachment springs, contact barriers. Terms see every DOF (x is 3 #V: free and kinematic), add their
// gradient to a full DOF vector and their Hessian entries to a shared layout (HessianValues), declare which
// vertices their Hessian couples (stencil), may bound a Newton step (max_step: the largest safe fraction,
// as continuous collision detection does for contact), may update lagged state when an iterate is
// accepted, and may follow a script in time (at_time). A Problem (problem.hpp) sums them. PolyFEM's summed forms are the model.
#include <limits>
#include <string_view>

#include <Eigen/Core>

#include "snh/fem/hessian_layout.hpp"
#include "snh/material/psd_projection.hpp"

namespace snh {

/// What the contact terms report for a frame (stats.json's contact columns): their active pairs and the
/// smallest distance among them at the state reported, and what they did since they last reported.
struct ContactStatistics {
  int pairs = 0;                                                    ///< active pairs (points within d̂ of a collider count one each)
  double min_distance = std::numeric_limits<double>::quiet_NaN();  ///< of an active pair; NaN without any
  long long ccd_calls = 0;                                          ///< step bounds asked (max_step)
  long long ccd_tests = 0;                                          ///< primitive pairs or points they tested
  double seconds = 0.0;                                             ///< wall time in the contact terms
};

class Term {
 public:
  virtual ~Term() = default;
  /// A short name for messages ("elastic", "inertia", "contact").
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// The energy at x (3 #V, every DOF); +∞ where x is outside the term's domain.
  [[nodiscard]] virtual double energy(const Eigen::VectorXd& x) const = 0;
  /// The energy; adds ∂E/∂x (every DOF, 3 #V) to *gradient and the Hessian's entries to *hessian (each
  /// skipped when null; only DOFs the layout numbers). `projection` asks for per-element (per-pair) PSD
  /// projection where the term has one. Returns +∞ outside the domain (gradient and Hessian then not
  /// meaningful).
  virtual double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                          PsdProjection projection) const = 0;
  /// The vertices its Hessian couples at x, beyond each DOF with itself (left empty by terms with a
  /// diagonal Hessian).
  virtual void stencil(const Eigen::VectorXd& /*x*/, Stencil& /*out*/) const {}
  /// True if the stencil depends on x (contact pairs): it is then asked at every evaluation, and the
  /// layout grows when it is not covered. A fixed stencil is asked once.
  [[nodiscard]] virtual bool stencil_varies() const { return false; }
  /// What a new layout should cover for a varying stencil: the stencil at x and what it may couple soon
  /// (contact: the pairs within a wider distance than d̂), so that a layout, once rebuilt, serves the next
  /// iterates and frames too. A rebuild costs what the whole elastic pattern costs (the layout, every
  /// term's bind(), the linear solver's analysis), the few entries more cost almost nothing. The stencil
  /// itself by default.
  virtual void stencil_ahead(const Eigen::VectorXd& x, Stencil& out) const { stencil(x, out); }
  /// Called when the problem's layout is (re)built, before any evaluation with it: a term that scatters
  /// through precomputed value indices computes them here.
  virtual void bind(const HessianLayout& /*layout*/) {}
  /// The largest α in (0, 1] such that x + α dx is safe for this term (dx: a step on every DOF, 0 on the
  /// kinematic ones); 1 by default. Newton starts its line search at the smallest over all terms.
  [[nodiscard]] virtual double max_step(const Eigen::VectorXd& /*x*/, const Eigen::VectorXd& /*dx*/) const { return 1.0; }
  /// Called with every iterate Newton accepts (Newton evaluated the energy and gradient there before this
  /// call and keeps them: a term must not change its energy here).
  virtual void on_accepted(const Eigen::VectorXd& /*x*/) {}
  /// Called before each solve with the time it solves for: a term whose data follow a script (a soft
  /// binding's targets carried by bones, a moving collider) updates them here.
  virtual void at_time(double /*t*/) {}
  /// Called before each solve, after at_time(t1), with the state the solve starts from (the last solution,
  /// at time t0; kinematic DOFs where they were then) and the time it solves for: a term with lagged data
  /// (friction: the normal forces and tangents of the step's start) takes them here.
  virtual void begin_step(const Eigen::VectorXd& /*x*/, double /*t0*/, double /*t1*/) {}
  /// True for a term whose energy is a function of the slip from where begin_step() found the state
  /// (friction): its force at that state is zero, and its force at a velocity v is the one at x + (t1 − t0) v.
  [[nodiscard]] virtual bool lagged() const { return false; }
  /// True for a contact term (self-contact, a collider): it has statistics to report.
  [[nodiscard]] virtual bool reports_contact() const { return false; }
  /// A contact term adds its statistics at x to `into` and starts counting anew; others add nothing.
  virtual void report_contact(const Eigen::VectorXd& /*x*/, ContactStatistics& /*into*/) {}
  /// True for a term whose data move with time (a moving collider).
  [[nodiscard]] virtual bool moving() const { return false; }
  /// A moving term: the largest fraction α ∈ [0, 1] of the joint motion — the state from x to x + dx (every
  /// DOF) while the term's data move from where they are at t0 to where they are at t1 — that keeps clear
  /// (its distances kept above a fraction of their start); 0 when x is not clear at t0. 1 by default.
  [[nodiscard]] virtual double sweep(const Eigen::VectorXd& /*x*/, const Eigen::VectorXd& /*dx*/, double /*t0*/,
                                     double /*t1*/) const {
    return 1.0;
  }
};

}  // namespace snh
