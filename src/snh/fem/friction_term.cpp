#include "snh/fem/friction_term.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include "snh/contact/barrier.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"
#include "snh/fem/hessian_layout.hpp"

namespace snh {
namespace {

void check(bool ok, const char* what, double value) {
  if (!ok) throw std::invalid_argument(fmt::format("friction: {} = {:g} must be finite and > 0", what, value));
}

/// The slip function at y = |u| for the threshold ε: f0, f1(y)/y (the gradient's factor of u) and
/// (f1/y)'(y)/y (the Hessian's factor of u uᵀ: −1/y³ from ε on, −1/(y ε²) below; 0 at y = 0, where u uᵀ
/// vanishes faster than the factor grows).
struct Slip {
  double over_y;  ///< f1(y)/y
  double outer;   ///< (f1/y)'(y)/y
  double f0;
};
Slip slip(double y, double eps) {
  if (y >= eps) return {1.0 / y, -1.0 / (y * y * y), y};
  return {2.0 / eps - y / (eps * eps), y > 0.0 ? -1.0 / (y * eps * eps) : 0.0, -y * y * y / (3.0 * eps * eps) + y * y / eps + eps / 3.0};
}

/// The closest points of segments p0p1 and q0q1 as parameters (s, t) in [0, 1]² (clamped; for parallel
/// segments one of the closest pairs).
std::pair<double, double> segment_closest(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  const Vec3 d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  if (a <= 0.0 && e <= 0.0) return {0.0, 0.0};
  if (a <= 0.0) return {0.0, std::clamp(f / e, 0.0, 1.0)};
  const double c = d1.dot(r);
  if (e <= 0.0) return {std::clamp(-c / a, 0.0, 1.0), 0.0};
  const double b = d1.dot(d2), denom = a * e - b * b;
  double s = denom > 1e-14 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = std::clamp(-c / a, 0.0, 1.0);
  } else if (t > 1.0) {
    t = 1.0;
    s = std::clamp((b - c) / a, 0.0, 1.0);
  }
  return {s, t};
}

}  // namespace

// ---- the lagged slips' energy

LaggedFrictionTerm::LaggedFrictionTerm(double mu, double velocity) : mu_(mu), velocity_(velocity) {
  check(std::isfinite(velocity) && velocity > 0.0, "the sticking velocity", velocity);
  if (!(std::isfinite(mu) && mu >= 0.0))
    throw std::invalid_argument(fmt::format("friction: the coefficient {:g} must be finite and >= 0", mu));
}

double LaggedFrictionTerm::normal_force() const {
  double sum = 0.0;
  for (const LaggedSlip& l : lagged_) sum += l.mu_lambda;
  return mu_ > 0.0 ? sum / mu_ : 0.0;
}

double LaggedFrictionTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double LaggedFrictionTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                                    PsdProjection /*projection: PSD as it stands*/) const {
  double e = 0.0;
  for (const LaggedSlip& l : lagged_) {
    Vec3 moved = -l.anchor;
    for (std::size_t m = 0; m < l.vertex.size(); ++m) {
      const Eigen::Index v = l.vertex[m];
      if (3 * v + 3 > x.size()) throw std::logic_error(fmt::format("friction: vertex {} is beyond the {} DOFs given", v, x.size()));
      moved += l.coef[m] * x.segment<3>(3 * v);
    }
    const Vec3 u = l.tangent * moved;
    if (!u.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    const double y = u.norm();
    const Slip f = slip(y, epsilon_);
    e += l.mu_lambda * f.f0;
    if (gradient) {
      const Vec3 g = (l.mu_lambda * f.over_y) * u;  // T u = u
      for (std::size_t m = 0; m < l.vertex.size(); ++m) gradient->segment<3>(3 * l.vertex[m]) += l.coef[m] * g;
    }
    if (hessian) {
      const Mat3 H = l.mu_lambda * (f.over_y * l.tangent + f.outer * u * u.transpose());
      for (std::size_t a = 0; a < l.vertex.size(); ++a)
        for (std::size_t b = a; b < l.vertex.size(); ++b) {
          // Two coefficients on one vertex add their cross terms to its diagonal block.
          const double w = l.coef[a] * l.coef[b] * (a != b && l.vertex[a] == l.vertex[b] ? 2.0 : 1.0);
          hessian->add_block(l.vertex[a], l.vertex[b], w * H);
        }
    }
  }
  return e;
}

// ---- against a collider

FrictionTerm::FrictionTerm(EmbeddedPoints points, ColliderShape shape, ColliderPose pose, double dhat, double stiffness, double mu,
                           double velocity)
    : LaggedFrictionTerm(mu, velocity), points_(std::move(points)), shape_(shape), pose_(std::move(pose)), dhat_(dhat),
      kappa_(stiffness) {
  check(std::isfinite(dhat) && dhat > 0.0, "dhat", dhat);
  check(std::isfinite(stiffness) && stiffness > 0.0, "the stiffness", stiffness);
}

void FrictionTerm::begin_step(const Eigen::VectorXd& x, double t0, double t1) {
  lagged_.clear();
  epsilon_ = velocity_ * (t1 - t0);
  if (!(epsilon_ > 0.0) || mu_ == 0.0 || !x.allFinite()) return;  // no step in time, or no friction
  const ColliderFrame at0 = collider_frame(pose_, t0);
  const Eigen::Affine3d carry = pose_ ? Eigen::Affine3d(pose_(t1) * pose_(t0).inverse()) : Eigen::Affine3d::Identity();
  const double s_hat = dhat_ * dhat_;
  const Eigen::MatrixXi& vertex = points_.vertex();
  const Eigen::MatrixXd& weight = points_.weight();
  for (Eigen::Index i = 0; i < points_.size(); ++i) {
    const Vec3 p = points_.point(x, i);
    const ShapeDistance sd = shape_distance(shape_, at0.to_base(p));
    const double d = at0.scale * sd.distance, s = d * d;
    if (!(d > 0.0) || !(s < s_hat)) continue;
    const double lambda = -2.0 * kappa_ * d * contact::barrier_first_derivative(s, s_hat);
    if (!(lambda > 0.0)) continue;
    const Vec3 n = (carry.linear() * (at0.rotation * sd.normal)).normalized();
    LaggedSlip l;
    l.vertex.assign(vertex.col(i).data(), vertex.col(i).data() + vertex.rows());
    l.coef.assign(weight.col(i).data(), weight.col(i).data() + weight.rows());
    l.anchor = carry * p;
    l.tangent = Mat3::Identity() - n * n.transpose();
    l.mu_lambda = mu_ * lambda;
    lagged_.push_back(std::move(l));
  }
}

void FrictionTerm::stencil(const Eigen::VectorXd& /*x*/, Stencil& out) const {
  out.vertices.clear();
  out.arity = 0;
  if (points_.arity() < 2) return;  // plain vertices: 3 by 3 blocks on the diagonal
  out.arity = static_cast<int>(points_.arity());
  out.vertices.assign(points_.vertex().data(), points_.vertex().data() + points_.vertex().size());
}

// ---- between self-contact pairs

SelfFrictionTerm::SelfFrictionTerm(std::shared_ptr<const ContactTerm> contact, EmbeddedPoints points, double dhat, double stiffness,
                                   double mu, double velocity)
    : LaggedFrictionTerm(mu, velocity), contact_(std::move(contact)), points_(std::move(points)), dhat_(dhat), kappa_(stiffness) {
  if (!contact_) throw std::invalid_argument("friction: no contact term");
  check(std::isfinite(dhat) && dhat > 0.0, "dhat", dhat);
  check(std::isfinite(stiffness) && stiffness > 0.0, "the stiffness", stiffness);
}

void SelfFrictionTerm::begin_step(const Eigen::VectorXd& x, double t0, double t1) {
  lagged_.clear();
  epsilon_ = velocity_ * (t1 - t0);
  if (!(epsilon_ > 0.0) || mu_ == 0.0 || !x.allFinite()) return;
  const double s_hat = dhat_ * dhat_;
  using Kind = ContactPair::Kind;
  for (const ContactPair& pair : contact_->pairs(x)) {
    const int n = pair.arity();
    std::array<Vec3, 4> P;
    for (int j = 0; j < n; ++j) {
      if (pair.vertices[j] >= points_.size())
        throw std::logic_error(fmt::format("friction: contact point {} is beyond the {} points given", pair.vertices[j], points_.size()));
      P[j] = points_.point(x, pair.vertices[j]);
    }
    // The closest points' coefficients on the pair's points: Σ a_j P_j = (closest on one) − (closest on the other).
    std::array<double, 4> a{1.0, 0.0, 0.0, 0.0};
    double mollifier = 1.0;
    switch (pair.kind) {
      case Kind::point_point: a[1] = -1.0; break;
      case Kind::point_edge: {
        const Vec3 e = P[2] - P[1];
        const double t = e.squaredNorm() > 0.0 ? std::clamp((P[0] - P[1]).dot(e) / e.squaredNorm(), 0.0, 1.0) : 0.0;
        a[1] = -(1.0 - t);
        a[2] = -t;
        break;
      }
      case Kind::point_triangle: {
        const Vec3 e1 = P[2] - P[1], e2 = P[3] - P[1], r = P[0] - P[1];
        Eigen::Matrix2d G;
        G << e1.dot(e1), e1.dot(e2), e1.dot(e2), e2.dot(e2);
        const Eigen::Vector2d beta = G.ldlt().solve(Eigen::Vector2d(e1.dot(r), e2.dot(r)));
        a[1] = -(1.0 - beta[0] - beta[1]);
        a[2] = -beta[0];
        a[3] = -beta[1];
        break;
      }
      case Kind::edge_edge: {
        const auto [s, t] = segment_closest(P[0], P[1], P[2], P[3]);
        a = {1.0 - s, s, -(1.0 - t), -t};
        mollifier = contact::edge_edge_mollifier(P[0], P[1], P[2], P[3], pair.mollifier_threshold);
        break;
      }
    }
    Vec3 gap = Vec3::Zero();
    for (int j = 0; j < n; ++j) gap += a[j] * P[j];
    const double d = gap.norm(), s = d * d;
    if (!(d > 0.0) || !(s < s_hat)) continue;
    const double lambda = -2.0 * kappa_ * pair.weight * mollifier * d * contact::barrier_first_derivative(s, s_hat);
    if (!(lambda > 0.0)) continue;
    const Vec3 normal = gap / d;
    LaggedSlip l;
    l.anchor = gap;  // u = T (Σ a_j p_j − Σ a_j P_j)
    l.tangent = Mat3::Identity() - normal * normal.transpose();
    l.mu_lambda = mu_ * lambda;
    for (int j = 0; j < n; ++j)
      for (Eigen::Index k = 0; k < points_.arity(); ++k) {
        l.vertex.push_back(points_.vertex()(k, pair.vertices[j]));
        l.coef.push_back(a[j] * points_.weight()(k, pair.vertices[j]));
      }
    lagged_.push_back(std::move(l));
  }
}

void SelfFrictionTerm::stencil(const Eigen::VectorXd& /*x*/, Stencil& out) const {
  out.arity = 2;
  out.vertices.clear();
  for (const LaggedSlip& l : lagged_)
    for (std::size_t i = 0; i < l.vertex.size(); ++i)
      for (std::size_t j = i + 1; j < l.vertex.size(); ++j)
        if (l.vertex[i] != l.vertex[j]) out.vertices.insert(out.vertices.end(), {l.vertex[i], l.vertex[j]});
}

}  // namespace snh
