// Projected Newton on toy problems: trials outside an energy's domain (+∞) shorten the step and never
// enter the state, a term's step bound starts the line search, accepted iterates reach the terms, and the
// step-size stopping rule, the looser linear solves an inexact solver is allowed (and the tighter ones where
// the last step's model held), one Hessian per Newton step, and full steps doubled where the projected Hessian
// overestimates the curvature.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "snh/fem/problem.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/newton.hpp"

namespace snh {
namespace {

/// E(x) = Σ_i a (x_i − b) − μ log(x_i − b): defined for x_i > b (+∞ elsewhere), minimised at b + μ/a. A full
/// Newton step from x_i − b = s lands at 2s − a s²/μ, outside the domain for s > 2μ/a. With `bounded`,
/// max_step keeps every x_i above b (a tenth of the way left), as a contact term's CCD would.
class Barrier final : public Term {
 public:
  Barrier(double b, double a, double mu, bool bounded) : b_(b), a_(a), mu_(mu), bounded_(bounded) {}
  std::string_view name() const override { return "barrier"; }
  double energy(const Eigen::VectorXd& x) const override { return evaluate(x, nullptr, nullptr, PsdProjection::none); }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, const HessianValues* H, PsdProjection) const override {
    ++evaluations;
    if (H) ++hessians;
    double E = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double s = x[i] - b_;
      if (!(s > 0.0)) {
        ++outside;
        return std::numeric_limits<double>::infinity();
      }
      E += a_ * s - mu_ * std::log(s);
      if (g) (*g)[i] += a_ - mu_ / s;
      if (H) {
        Mat3 block = Mat3::Zero();
        block(i % 3, i % 3) = mu_ / (s * s);
        H->add_block(static_cast<int>(i / 3), static_cast<int>(i / 3), block);
      }
    }
    return E;
  }
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override {
    if (!bounded_) return 1.0;
    double alpha = 1.0;
    for (Eigen::Index i = 0; i < x.size(); ++i)
      if (dx[i] < 0.0) alpha = std::min(alpha, 0.9 * (x[i] - b_) / -dx[i]);
    ++bounds;
    return alpha;
  }
  void on_accepted(const Eigen::VectorXd& x) override {
    ++accepted;
    last_accepted = x;
  }
  mutable int evaluations = 0, outside = 0, bounds = 0, hessians = 0;
  int accepted = 0;
  Eigen::VectorXd last_accepted;

 private:
  double b_, a_, mu_;
  bool bounded_;
};

/// Two vertices, every DOF free, b = 0, a = μ = 1 (minimum at 1); starting values above 2 overshoot.
struct Toy {
  explicit Toy(bool bounded) : term(0.0, 1.0, 1.0, bounded), problem(DofMap(std::vector<std::uint8_t>(6, 0))) {
    problem.add(term);
  }
  Barrier term;
  Problem problem;
};

NewtonOptions options(int max_iterations, double tolerance, double step_tolerance = 0.0) {
  NewtonOptions o;
  o.max_iterations = max_iterations;
  o.tolerance = tolerance;
  o.step_tolerance = step_tolerance;
  return o;
}

const Eigen::VectorXd kStart = (Eigen::VectorXd(6) << 40.0, 0.5, 3.0, 7.0, 0.02, 1.5).finished();

TEST(Newton, TrialsOutsideTheDomainShortenTheStepAndNeverEnterTheState) {
  Toy toy(false);
  Eigen::VectorXd x = kStart;
  auto solver = make_linear_solver({.name = "ldlt"});
  const NewtonReport r = newton_solve(toy.problem, x, *solver, options(200, 1e-10));
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_GT(toy.term.outside, 0) << "some full steps left the domain";
  EXPECT_GT(r.line_search_steps, 0);
  EXPECT_TRUE(x.allFinite());
  EXPECT_TRUE((x.array() > 0.0).all());
  EXPECT_EQ(toy.term.accepted, r.iterations) << "every accepted iterate reaches the terms";
  EXPECT_EQ(toy.term.last_accepted, x);
  EXPECT_LE((x.array() - 1.0).abs().maxCoeff(), 1e-9);
}

TEST(Newton, TheLineSearchStartsAtTheTermsStepBound) {
  Toy free(false), bounded(true);
  Eigen::VectorXd a = kStart, b = kStart;
  auto s1 = make_linear_solver({.name = "ldlt"}), s2 = make_linear_solver({.name = "ldlt"});
  const NewtonReport ra = newton_solve(free.problem, a, *s1, options(200, 1e-10));
  const NewtonReport rb = newton_solve(bounded.problem, b, *s2, options(200, 1e-10));
  ASSERT_TRUE(ra.converged && rb.converged);
  EXPECT_EQ(bounded.term.outside, 0) << "the bound keeps every trial inside the domain";
  EXPECT_EQ(bounded.term.bounds, rb.iterations) << "asked once per Newton step";
  EXPECT_GT(free.term.outside, 0);
  EXPECT_LE((a - b).cwiseAbs().maxCoeff(), 1e-8) << "the same minimum";
}

TEST(Newton, AZeroStepBoundIsAFailureNotAHang) {
  class Stuck final : public Term {
   public:
    std::string_view name() const override { return "stuck"; }
    double energy(const Eigen::VectorXd& x) const override { return 0.5 * x.squaredNorm(); }
    double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, const HessianValues* H, PsdProjection) const override {
      if (g) *g += x;
      if (H)
        for (int v = 0; v < x.size() / 3; ++v) H->add_block(v, v, Mat3::Identity());
      return energy(x);
    }
    double max_step(const Eigen::VectorXd&, const Eigen::VectorXd&) const override { return 0.0; }
  } stuck;
  Problem p{DofMap(std::vector<std::uint8_t>(3, 0))};
  p.add(stuck);
  Eigen::VectorXd x = Eigen::Vector3d(1, 2, 3);
  auto solver = make_linear_solver({.name = "ldlt"});
  const NewtonReport r = newton_solve(p, x, *solver, {});
  EXPECT_FALSE(r.converged);
  EXPECT_EQ(r.failure, "no step is allowed at Newton iteration 1 (the step bound is 0)");
  EXPECT_EQ(x, Eigen::Vector3d(1, 2, 3));
}

TEST(Newton, StopsOnTheStepSizeWhenAskedOnlyWhereTheForcesAgree) {
  Toy toy(true);
  Eigen::VectorXd x = kStart;
  auto solver = make_linear_solver({.name = "ldlt"});
  // An unreachable residual tolerance: the step rule ends the solve only once the step is below the
  // coordinates' rounding (where ‖g‖ cannot fall further), at the minimum.
  const NewtonReport r =
      newton_solve(toy.problem, x, *solver, options(200, 1e-300, 1e-9));
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_LE((x.array() - 1.0).abs().maxCoeff(), 1e-12);
  // A tolerance a fifth of the residual at the third iterate, and a step rule any step meets: the solve
  // ends there, by the step rule, with ‖g‖ within 10 times the tolerance and above it; before issue 31 the
  // step rule ended it at the start, whatever the forces.
  ASSERT_GE(r.residuals.size(), 4u);
  const double tol = r.residuals[2] / 5.0;
  Toy loose(true);
  Eigen::VectorXd w = kStart;
  const NewtonReport s = newton_solve(loose.problem, w, *solver, options(200, tol, 1e3));
  ASSERT_TRUE(s.converged) << s.failure;
  EXPECT_TRUE(s.converged_by_step);
  EXPECT_EQ(s.iterations, 2);
  EXPECT_GT(s.residual, tol);
  EXPECT_LE(s.residual, 10.0 * tol);
  // Without it, the same solve stops only where the gradient is exactly zero, or runs out of iterations.
  Toy again(true);
  Eigen::VectorXd y = kStart;
  const NewtonReport q = newton_solve(again.problem, y, *solver, options(60, 1e-300));
  EXPECT_TRUE(!q.converged || q.residual == 0.0) << q.residual;
  EXPECT_FALSE(q.converged_by_step);
  // Relative to how far the solve has moved (the scenes' rule): the same minimum, no length to choose.
  Toy third(true);
  Eigen::VectorXd z = kStart;
  NewtonOptions relative = options(200, 1e-300);
  relative.relative_step_tolerance = 1e-8;
  const NewtonReport p = newton_solve(third.problem, z, *solver, relative);
  ASSERT_TRUE(p.converged) << p.failure;
  EXPECT_LE((z.array() - 1.0).abs().maxCoeff(), 1e-8);
}

TEST(Newton, AssemblesOneHessianPerNewtonStepAndNoneForAConvergedStart) {
  // The Hessian is made only once an iterate is known not to have converged: k Newton steps with the true
  // Hessian (positive definite here) assemble exactly k, and a start that is already converged none.
  Toy toy(true);
  Eigen::VectorXd x = kStart;
  auto solver = make_linear_solver({.name = "ldlt"});
  const NewtonReport r = newton_solve(toy.problem, x, *solver, options(200, 1e-10));
  ASSERT_TRUE(r.converged) << r.failure;
  ASSERT_GT(r.iterations, 2);
  EXPECT_EQ(r.true_hessian_steps, r.iterations);
  EXPECT_EQ(toy.term.hessians, r.iterations);
  toy.term.hessians = 0;
  const NewtonReport again = newton_solve(toy.problem, x, *solver, options(200, 1e-10));
  ASSERT_TRUE(again.converged);
  EXPECT_EQ(again.iterations, 0);
  EXPECT_EQ(toy.term.hessians, 0);
}

/// Per DOF, E = ½ x² + ¼ c x⁴ (a convex "element") − ½ (1 + δ) x² (a concave one, as an element compressed
/// or turned inside out has negative curvature): minimised at x² = δ / c, with the curvature −δ + 3 c x²,
/// negative near 0. Projected per element, the concave part's Hessian is clamped to 0, so the matrix says 1 + 3 c x²,
/// a hundred times the energy's curvature: each projected Newton step from x is only about δ x long.
class Clamped final : public Term {
 public:
  Clamped(double delta, double c) : delta_(delta), c_(c) {}
  std::string_view name() const override { return "clamped"; }
  double energy(const Eigen::VectorXd& x) const override { return evaluate(x, nullptr, nullptr, PsdProjection::none); }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, const HessianValues* H, PsdProjection p) const override {
    double E = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double v = x[i];
      E += 0.5 * v * v + 0.25 * c_ * v * v * v * v - 0.5 * (1.0 + delta_) * v * v;
      if (g) (*g)[i] += v + c_ * v * v * v - (1.0 + delta_) * v;
      if (H) {
        Mat3 block = Mat3::Zero();
        block(i % 3, i % 3) = 1.0 + 3.0 * c_ * v * v + (p == PsdProjection::none ? -(1.0 + delta_) : 0.0);
        H->add_block(static_cast<int>(i / 3), static_cast<int>(i / 3), block);
      }
    }
    return E;
  }

 private:
  double delta_, c_;
};

TEST(Newton, AFullStepWhoseSlopeStaysSteepIsDoubledWhereProjectionOverestimatesTheCurvature) {
  // δ = 0.01, c = 1: the minimum at x = 0.1; from 0.001 a projected Newton step grows x by about 1 %, so
  // full steps alone would take 444 iterations (the creep of the fist's contact frames, where the
  // cells between the fingers are compressed or turned inside out). The energy's slope at each full step is nearly
  // its slope at the start, and the line search doubles such a step.
  Clamped term(0.01, 1.0);
  Problem problem{DofMap(std::vector<std::uint8_t>(3, 0))};
  problem.add(term);
  Eigen::VectorXd x = Eigen::Vector3d(0.001, -0.002, 0.003);
  auto solver = make_linear_solver({.name = "ldlt"});
  const NewtonReport r = newton_solve(problem, x, *solver, options(40, 1e-12));
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_LE(r.iterations, 20);
  EXPECT_GT(r.line_search_expansions, 0);
  EXPECT_GT(r.true_hessian_steps, 0) << "near the minimum the energy is convex: plain Newton finishes";
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(std::abs(x[i]), 0.1, 1e-9) << i;
  // Where the matrix is the energy's curvature (the barrier, whose Hessian is exact and positive), the
  // slope at a full step has fallen by at least half: no step is doubled, and the iterates are unchanged.
  Toy toy(true);
  Eigen::VectorXd y = kStart;
  const NewtonReport q = newton_solve(toy.problem, y, *solver, options(200, 1e-10));
  ASSERT_TRUE(q.converged);
  EXPECT_EQ(q.line_search_expansions, 0);
}

/// A direct solver that records, per factorization, whether it was a try of a matrix that may be indefinite
/// (the true Hessian: 'T' where it factorized, 't' where it did not) or the projected Hessian's ('P'). A try
/// followed by 'P' failed: not factorized, or its direction was no descent.
class Tries final : public LinearSolver {
 public:
  Tries() : inner_(make_linear_solver({.name = "ldlt"})) {}
  double factorize(const SparseLower& A) override {
    calls += 'P';
    return inner_->factorize(A);
  }
  bool try_factorize(const SparseLower& A) override {
    const bool ok = inner_->try_factorize(A);
    calls += ok ? 'T' : 't';
    return ok;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override { return inner_->solve(b, enough); }
  std::string_view name() const override { return "tries"; }
  std::string calls;

 private:
  std::unique_ptr<LinearSolver> inner_;
};

TEST(Newton, AfterTheTrueHessianFailsTheNextIterationGoesStraightToTheProjectedOne) {
  // The clamped term's true Hessian is indefinite for |x| < 0.058: from 0.001 it fails, and each failed try
  // is followed by its projected Hessian ("tP", or "TP" where it factorized but gave no descent). The
  // iteration after a failure does not try again ("P" alone), the one after that does; near the minimum the
  // true Hessian serves ("T") to the end.
  Clamped term(0.01, 1.0);
  Problem problem{DofMap(std::vector<std::uint8_t>(3, 0))};
  problem.add(term);
  Eigen::VectorXd x = Eigen::Vector3d(0.001, -0.002, 0.003);
  Tries solver;
  const NewtonReport r = newton_solve(problem, x, solver, options(40, 1e-12));
  ASSERT_TRUE(r.converged) << r.failure;
  // One iteration per group: "T", "tP" or "TP" (a failed try, then the projected Hessian) or "P" (no try).
  std::vector<std::string> iterations;
  for (std::size_t k = 0; k < solver.calls.size();) {
    const std::size_t n = solver.calls[k] != 'P' && k + 1 < solver.calls.size() && solver.calls[k + 1] == 'P' ? 2 : 1;
    iterations.push_back(solver.calls.substr(k, n));
    k += n;
  }
  ASSERT_EQ(static_cast<int>(iterations.size()), r.iterations) << solver.calls;
  const auto failed = [](const std::string& it) { return it.size() == 2; };
  EXPECT_TRUE(failed(iterations.front())) << solver.calls;
  EXPECT_EQ(iterations.back(), "T") << solver.calls;
  int skipped = 0;
  for (std::size_t k = 0; k < iterations.size(); ++k) {
    ASSERT_TRUE(iterations[k] == "T" || failed(iterations[k]) || iterations[k] == "P") << solver.calls;
    if (k > 0) EXPECT_EQ(iterations[k] == "P", failed(iterations[k - 1])) << "iteration " << k + 1 << ": " << solver.calls;
    skipped += iterations[k] == "P";
  }
  EXPECT_GT(skipped, 0) << solver.calls;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(std::abs(x[i]), 0.1, 1e-9) << i;
}

/// A direct solver that says it may be inexact, and records the residual each solve was allowed.
class Recording final : public LinearSolver {
 public:
  explicit Recording(bool inexact) : inner_(make_linear_solver({.name = "ldlt"})), inexact_(inexact) {}
  double factorize(const SparseLower& A) override { return inner_->factorize(A); }
  bool try_factorize(const SparseLower& A) override { return inner_->try_factorize(A); }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    allowed.push_back(enough / b.norm());
    return inner_->solve(b, enough);
  }
  std::string_view name() const override { return "recording"; }
  bool inexact() const override { return inexact_; }
  std::vector<double> allowed;  ///< per solve, the allowed residual relative to ‖b‖ = ‖g‖

 private:
  std::unique_ptr<LinearSolver> inner_;
  bool inexact_;
};

TEST(Newton, AnInexactSolverIsAllowedATenthOfTheResidualAtFirstAndLessAsItFalls) {
  Toy toy(true), again(true);
  Eigen::VectorXd x = kStart, y = kStart;
  Recording inexact(true), exact(false);
  const NewtonReport r = newton_solve(toy.problem, x, inexact, options(200, 1e-10));
  const NewtonReport q = newton_solve(again.problem, y, exact, options(200, 1e-10));
  ASSERT_TRUE(r.converged && q.converged);
  ASSERT_GE(inexact.allowed.size(), 3u);
  // η = min(0.1, √(‖g‖/‖g₀‖)): a tenth while ‖g‖ is near its first value, then shrinking with √‖g‖.
  EXPECT_DOUBLE_EQ(inexact.allowed.front(), 0.1);
  EXPECT_LT(inexact.allowed.back(), 0.01);
  for (std::size_t k = 1; k < inexact.allowed.size(); ++k) EXPECT_LE(inexact.allowed[k], 0.1 * (1 + 1e-12));
  // A solver that is not inexact gets only the absolute bound (a tenth of the Newton tolerance).
  for (std::size_t k = 0; k < exact.allowed.size(); ++k) EXPECT_LT(exact.allowed[k], inexact.allowed[std::min(k, inexact.allowed.size() - 1)]);
  EXPECT_NEAR((x - y).lpNorm<Eigen::Infinity>(), 0.0, 1e-8);
}

/// An inexact solver that stops exactly where it is allowed to, as conjugate gradients do at their bound: the
/// exact solution scaled by 1 − θ, θ = enough / ‖b‖ (then ‖A x − b‖ = θ ‖b‖), and that residual reported.
class Loose final : public LinearSolver {
 public:
  /// `reports`: false hides the residual (NaN, as a direct solver), which leaves only the rule.
  explicit Loose(bool reports = true) : inner_(make_linear_solver({.name = "ldlt"})), reports_(reports) {}
  double factorize(const SparseLower& A) override { return inner_->factorize(A); }
  bool try_factorize(const SparseLower& A) override { return inner_->try_factorize(A); }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const double theta = std::min(1.0, enough / b.norm());
    allowed.push_back(theta);
    residual_ = theta * b.norm();
    return (1.0 - theta) * inner_->solve(b, 0.0);
  }
  double last_residual() const override { return reports_ ? residual_ : std::nan(""); }
  std::string_view name() const override { return "loose"; }
  bool inexact() const override { return true; }
  std::vector<double> allowed;  ///< per solve, the allowed residual relative to ‖b‖

 private:
  std::unique_ptr<LinearSolver> inner_;
  bool reports_;
  double residual_ = 0.0;
};

/// E = Σ_i ½ k_i (x_i − c_i)²: a quadratic, whose Newton model is exact.
class Springs final : public Term {
 public:
  std::string_view name() const override { return "springs"; }
  double energy(const Eigen::VectorXd& x) const override { return evaluate(x, nullptr, nullptr, PsdProjection::none); }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, const HessianValues* H, PsdProjection) const override {
    double E = 0.0;
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const double k = 1.0 + static_cast<double>(i), u = x[i] - 0.1 * static_cast<double>(i);
      E += 0.5 * k * u * u;
      if (g) (*g)[i] += k * u;
      if (H) {
        Mat3 block = Mat3::Zero();
        block(i % 3, i % 3) = k;
        H->add_block(static_cast<int>(i / 3), static_cast<int>(i / 3), block);
      }
    }
    return E;
  }
};

TEST(Newton, AnInexactSolveIsTightenedAtOnceWhereTheLastStepsLinearModelPredictedTheResidual) {
  // A quadratic: the first step, solved to a tenth, leaves exactly the linear residual it was allowed, so the
  // model's miss |‖g₁‖ − ‖g₀ + H d₀‖| is 0 (Eisenstat and Walker's first choice), and the second solve is
  // allowed only the absolute bound (a tenth of the tolerance): two Newton steps. The rule
  // min(0.1, √(‖g‖/‖g₀‖)) alone allows 0.1 again and takes seven (the same solver with its residual hidden).
  Springs springs;
  Problem quadratic{DofMap(std::vector<std::uint8_t>(6, 0))};
  quadratic.add(springs);
  Eigen::VectorXd x = kStart;
  Loose loose;
  const NewtonReport r = newton_solve(quadratic, x, loose, options(50, 1e-10));
  ASSERT_TRUE(r.converged) << r.failure;
  EXPECT_EQ(r.iterations, 2);
  ASSERT_EQ(loose.allowed.size(), 2u);
  EXPECT_DOUBLE_EQ(loose.allowed[0], 0.1);
  EXPECT_LE(loose.allowed[1] * r.residuals[1], 0.1 * 1e-10 * (1 + 1e-12));
  Eigen::VectorXd w = kStart;
  Loose rule_only(false);
  const NewtonReport s = newton_solve(quadratic, w, rule_only, options(50, 1e-10));
  ASSERT_TRUE(s.converged) << s.failure;
  EXPECT_EQ(s.iterations, 7);
  // Nonlinear (the barrier): the model misses, and the solves stay loose while it does, never looser than the
  // rule; the same minimum as an exact solver's.
  Toy toy(true), again(true);
  Eigen::VectorXd y = kStart, z = kStart;
  Loose nonlinear;
  Recording rule(true);
  const NewtonReport q = newton_solve(toy.problem, y, nonlinear, options(200, 1e-10));
  const NewtonReport p = newton_solve(again.problem, z, rule, options(200, 1e-10));
  ASSERT_TRUE(q.converged && p.converged);
  ASSERT_GE(nonlinear.allowed.size(), 3u);
  EXPECT_GT(nonlinear.allowed[1], 0.01) << "far from the minimum the barrier's model misses by much";
  for (std::size_t k = 0; k < nonlinear.allowed.size(); ++k) {  // the rule, or the absolute bound where larger
    const double rule = std::max(std::min(0.1, std::sqrt(q.residuals[k] / q.residuals[0])), 0.1 * 1e-10 / q.residuals[k]);
    EXPECT_LE(nonlinear.allowed[k], rule * (1 + 1e-12)) << k;
  }
  EXPECT_NEAR((y - z).lpNorm<Eigen::Infinity>(), 0.0, 1e-8);
}

}  // namespace
}  // namespace snh
