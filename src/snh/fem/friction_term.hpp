#pragma once
// Lagged Coulomb friction against a kinematic collider (IPC, Li et al. 2020, §5): the dissipative potential
// of points sliding on a plane or a convex shape (collider_term.hpp's ColliderShape, with its pose in time),
// with a smooth transition from static to dynamic friction. What the step starts from is frozen ("lagged")
// for the solve, at begin_step(x_t, t0, t1): for each point p_t = W x_t within d̂ of the collider, its
// normal force λ = −κ ∂b(d², d̂²)/∂d = −2 κ d b'(d²) (the barrier's push, collider_term.hpp), the unit normal n
// at its closest point, and its anchor c = M p_t, where M = pose(t1) pose(t0)⁻¹ carries the collider's
// frame from t0 to t1 (a point stuck to a moving collider goes where the collider takes it); the tangent
// projector T = I − n' n'ᵀ of the carried normal n' = M n (its rotation). In the solve, each such point adds
//     D(p) = μ λ f0(|u|),   u = T (p − c)   (the tangential slip over the step)
// with f0(y) = y for y ≥ ε and −y³/(3ε²) + y²/ε + ε/3 below (C¹; f0' = f1 = min(2y/ε − y²/ε², 1)), ε = ε_v h the
// slip below which the point counts as sticking (ε_v a velocity, h = t1 − t0). Gradient μ λ (f1(y)/y) u;
// Hessian μ λ [(f1/y) T + (f1/y)' u uᵀ / y]: for y ≥ ε, μ λ / y (T − û ûᵀ), for y < ε, μ λ [(2/ε − y/ε²) T −
// u uᵀ /(y ε²)], whose eigenvalues are 2(ε − y)/ε², 2/ε − y/ε² and 0 (along n): positive semi-definite
// as it stands (D is convex in p), no projection needed. Points are embedded as the contact terms' (p =
// Σ_k w_k x_{v_k}; one weight of 1 for a plain vertex): g_x = Wᵀ g_p, H_x = Wᵀ H_p W.
// The force resisting slip is at most μ λ (|∇D| = μ λ f1 ≤ μ λ), reached past ε: Coulomb's law with the
// normal force of the step's start. One lagged pass (the normal force and tangent are not updated and the
// step solved again, as IPC can): the friction is exact where the normal force changes little over a step.
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/fem/embedded_points.hpp"
#include "snh/fem/term.hpp"
#include "snh/math/types.hpp"

namespace snh {

/// One lagged slip: u = T (Σ_m a_m x_{v_m} − c), its weight μλ (what both friction terms add up).
struct LaggedSlip {
  std::vector<int> vertex;    ///< volume vertices
  std::vector<double> coef;   ///< a_m
  Vec3 anchor = Vec3::Zero(); ///< c
  Mat3 tangent = Mat3::Identity();
  double mu_lambda = 0.0;
};

/// The energy Σ μλ f0(|u|) of lagged slips (above), set by begin_step; derivatives through the coefficients
/// (g_m = a_m μλ (f1/y) u, H_mn = a_m a_n H_u), PSD as they stand.
class LaggedFrictionTerm : public Term {
 public:
  [[nodiscard]] std::string_view name() const override { return "friction"; }
  [[nodiscard]] bool lagged() const override { return true; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  /// The slips lagged at the step's start, and the sum of their normal forces λ.
  [[nodiscard]] int lagged_points() const { return static_cast<int>(lagged_.size()); }
  [[nodiscard]] double normal_force() const;
  /// The sticking slip ε = ε_v h of this step.
  [[nodiscard]] double epsilon() const { return epsilon_; }
  [[nodiscard]] const std::vector<LaggedSlip>& slips() const { return lagged_; }

 protected:
  /// Checks μ (≥ 0) and ε_v (> 0); one line.
  LaggedFrictionTerm(double mu, double velocity);
  double mu_, velocity_;
  double epsilon_ = 0.0;
  std::vector<LaggedSlip> lagged_;
};

class FrictionTerm final : public LaggedFrictionTerm {
 public:
  /// points          the points that slide on the collider (plain vertices, or points embedded in the volume)
  /// shape, pose     the collider (as ShapeColliderTerm's; an empty pose: fixed)
  /// dhat, stiffness the collider's barrier (the normal force is its push)
  /// mu              the friction coefficient (≥ 0)
  /// velocity        ε_v (> 0): slip slower than this counts as sticking
  /// Throws std::invalid_argument (one line) for μ negative or not finite, or d̂, κ, ε_v not finite and > 0.
  FrictionTerm(EmbeddedPoints points, ColliderShape shape, ColliderPose pose, double dhat, double stiffness, double mu,
               double velocity);

  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  void begin_step(const Eigen::VectorXd& x, double t0, double t1) override;

 private:
  EmbeddedPoints points_;
  ColliderShape shape_;
  ColliderPose pose_;
  double dhat_, kappa_;
};

/// Friction between the pairs of a self-contact term (ContactTerm), IPC's: at the step's start, each pair in
/// range (point–point, point–edge, point–triangle, edge–edge, merged as the term merges them) takes its
/// normal force λ = −κ w ∂(m b)/∂d (w the pair's weight, m the edge–edge mollifier, 1 otherwise; its
/// derivative left out, as IPC does), the closest points' coefficients on its points (a = +1 … on one side,
/// −barycentric weights on the other: Σ a_j p_j is the vector between the closest points) and the tangent
/// plane normal to that vector; the slip is the relative tangential motion of the closest points,
/// u = T Σ a_j (p_j − p_j(t0)). Points are the surface's (embedded through their weights, as the term's).
class SelfFrictionTerm final : public LaggedFrictionTerm {
 public:
  /// contact         the self-contact term (its pairs are asked at each step's start)
  /// points          the surface's points as the term has them (its pairs' ids are theirs)
  /// dhat, stiffness the term's d̂ and κ
  /// Throws std::invalid_argument (one line) as FrictionTerm, or for a null term.
  SelfFrictionTerm(std::shared_ptr<const ContactTerm> contact, EmbeddedPoints points, double dhat, double stiffness, double mu,
                   double velocity);

  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  [[nodiscard]] bool stencil_varies() const override { return true; }
  void begin_step(const Eigen::VectorXd& x, double t0, double t1) override;

 private:
  std::shared_ptr<const ContactTerm> contact_;
  EmbeddedPoints points_;
  double dhat_, kappa_;
};

}  // namespace snh
