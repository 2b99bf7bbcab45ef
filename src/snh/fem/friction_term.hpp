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
#include <vector>

#include <Eigen/Core>

#include "snh/fem/collider_term.hpp"
#include "snh/fem/term.hpp"
#include "snh/math/types.hpp"

namespace snh {

class FrictionTerm final : public Term {
 public:
  /// vertex, weight  k by #points: each point's volume vertices and weights (k = 1, weight 1: plain vertices)
  /// shape, pose     the collider (as ShapeColliderTerm's; an empty pose: fixed)
  /// dhat, stiffness the collider's barrier (the normal force is its push)
  /// mu              the friction coefficient (≥ 0)
  /// velocity        ε_v (> 0): slip slower than this counts as sticking
  /// Throws std::invalid_argument (one line) for sizes that differ, a negative vertex id, non-finite
  /// weights, μ negative or not finite, or d̂, κ, ε_v not finite and > 0.
  FrictionTerm(Eigen::MatrixXi vertex, Eigen::MatrixXd weight, ColliderShape shape, ColliderPose pose, double dhat,
               double stiffness, double mu, double velocity);
  /// Plain vertices.
  FrictionTerm(const std::vector<int>& vertices, ColliderShape shape, ColliderPose pose, double dhat, double stiffness,
               double mu, double velocity);

  [[nodiscard]] std::string_view name() const override { return "friction"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  void begin_step(const Eigen::VectorXd& x, double t0, double t1) override;

  /// The points in contact at the step's start, and the sum of their normal forces λ.
  [[nodiscard]] int lagged_points() const { return static_cast<int>(lagged_.size()); }
  [[nodiscard]] double normal_force() const;
  /// The sticking slip ε = ε_v h of this step.
  [[nodiscard]] double epsilon() const { return epsilon_; }

 private:
  struct Lagged {
    Eigen::Index point;
    double lambda;  ///< μ λ
    Mat3 tangent;   ///< T
    Vec3 anchor;    ///< c
  };
  [[nodiscard]] Vec3 point_at(const Eigen::VectorXd& x, Eigen::Index i) const;
  Eigen::MatrixXi vertex_;
  Eigen::MatrixXd weight_;
  ColliderShape shape_;
  ColliderPose pose_;
  double dhat_, kappa_, mu_, velocity_;
  double epsilon_ = 0.0;
  std::vector<Lagged> lagged_;
};

}  // namespace snh
