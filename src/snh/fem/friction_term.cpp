#include "snh/fem/friction_term.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "snh/contact/barrier.hpp"
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

}  // namespace

FrictionTerm::FrictionTerm(Eigen::MatrixXi vertex, Eigen::MatrixXd weight, ColliderShape shape, ColliderPose pose, double dhat,
                           double stiffness, double mu, double velocity)
    : vertex_(std::move(vertex)), weight_(std::move(weight)), shape_(shape), pose_(std::move(pose)), dhat_(dhat),
      kappa_(stiffness), mu_(mu), velocity_(velocity) {
  if (vertex_.rows() != weight_.rows() || vertex_.cols() != weight_.cols())
    throw std::invalid_argument(fmt::format("friction: {} by {} vertex ids but {} by {} weights", vertex_.rows(), vertex_.cols(),
                                            weight_.rows(), weight_.cols()));
  if (vertex_.size() > 0 && vertex_.minCoeff() < 0) throw std::invalid_argument("friction: a negative vertex id");
  if (!weight_.allFinite()) throw std::invalid_argument("friction: a weight that is not finite");
  check(std::isfinite(dhat) && dhat > 0.0, "dhat", dhat);
  check(std::isfinite(stiffness) && stiffness > 0.0, "the stiffness", stiffness);
  check(std::isfinite(velocity) && velocity > 0.0, "the sticking velocity", velocity);
  if (!(std::isfinite(mu) && mu >= 0.0))
    throw std::invalid_argument(fmt::format("friction: the coefficient {:g} must be finite and >= 0", mu));
}

FrictionTerm::FrictionTerm(const std::vector<int>& vertices, ColliderShape shape, ColliderPose pose, double dhat, double stiffness,
                           double mu, double velocity)
    : FrictionTerm(Eigen::Map<const Eigen::RowVectorXi>(vertices.data(), static_cast<Eigen::Index>(vertices.size())),
                   Eigen::MatrixXd::Ones(1, static_cast<Eigen::Index>(vertices.size())), shape, std::move(pose), dhat, stiffness, mu,
                   velocity) {}

Vec3 FrictionTerm::point_at(const Eigen::VectorXd& x, Eigen::Index i) const {
  Vec3 p = Vec3::Zero();
  for (Eigen::Index k = 0; k < vertex_.rows(); ++k) {
    const Eigen::Index v = vertex_(k, i);
    if (3 * v + 3 > x.size()) throw std::logic_error(fmt::format("friction: vertex {} is beyond the {} DOFs given", v, x.size()));
    p += weight_(k, i) * x.segment<3>(3 * v);
  }
  return p;
}

void FrictionTerm::begin_step(const Eigen::VectorXd& x, double t0, double t1) {
  lagged_.clear();
  epsilon_ = velocity_ * (t1 - t0);
  if (!(epsilon_ > 0.0) || mu_ == 0.0 || !x.allFinite()) return;  // no step in time, or no friction
  const Eigen::Affine3d at0 = pose_ ? pose_(t0) : Eigen::Affine3d::Identity();
  const Eigen::Affine3d carry = pose_ ? Eigen::Affine3d(pose_(t1) * at0.inverse()) : Eigen::Affine3d::Identity();
  const double scale = at0.linear().col(0).norm();  // a similarity (ShapeColliderTerm checks the pose)
  const Mat3 rotation = at0.linear() / scale;
  const double s_hat = dhat_ * dhat_;
  for (Eigen::Index i = 0; i < vertex_.cols(); ++i) {
    const Vec3 p = point_at(x, i);
    const ShapeDistance sd = shape_distance(shape_, rotation.transpose() * (p - at0.translation()) / scale);
    const double d = scale * sd.distance, s = d * d;
    if (!(d > 0.0) || !(s < s_hat)) continue;
    const double lambda = -2.0 * kappa_ * d * contact::barrier_first_derivative(s, s_hat);
    if (!(lambda > 0.0)) continue;
    const Vec3 n = (carry.linear() * (rotation * sd.normal)).normalized();
    lagged_.push_back({i, mu_ * lambda, Mat3::Identity() - n * n.transpose(), carry * p});
  }
}

double FrictionTerm::normal_force() const {
  double sum = 0.0;
  for (const Lagged& l : lagged_) sum += l.lambda;
  return mu_ > 0.0 ? sum / mu_ : 0.0;
}

double FrictionTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double FrictionTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                              PsdProjection /*projection: PSD as it stands*/) const {
  double e = 0.0;
  for (const Lagged& l : lagged_) {
    const Vec3 u = l.tangent * (point_at(x, l.point) - l.anchor);
    if (!u.allFinite()) return std::numeric_limits<double>::quiet_NaN();
    const double y = u.norm();
    const Slip f = slip(y, epsilon_);
    e += l.lambda * f.f0;
    if (gradient) {
      const Vec3 g = (l.lambda * f.over_y) * u;  // T u = u
      for (Eigen::Index k = 0; k < vertex_.rows(); ++k) gradient->segment<3>(3 * vertex_(k, l.point)) += weight_(k, l.point) * g;
    }
    if (hessian) {
      const Mat3 H = l.lambda * (f.over_y * l.tangent + f.outer * u * u.transpose());
      for (Eigen::Index a = 0; a < vertex_.rows(); ++a)
        for (Eigen::Index b = a; b < vertex_.rows(); ++b) {
          const int va = vertex_(a, l.point), vb = vertex_(b, l.point);
          // Two weights on one vertex add their cross terms to its diagonal block (as PlaneContactTerm).
          const double w = weight_(a, l.point) * weight_(b, l.point) * (a != b && va == vb ? 2.0 : 1.0);
          hessian->add_block(va, vb, w * H);
        }
    }
  }
  return e;
}

void FrictionTerm::stencil(const Eigen::VectorXd& /*x*/, Stencil& out) const {
  out.vertices.clear();
  out.arity = 0;
  if (vertex_.rows() < 2) return;  // plain vertices: 3 by 3 blocks on the diagonal
  out.arity = static_cast<int>(vertex_.rows());
  out.vertices.assign(vertex_.data(), vertex_.data() + vertex_.size());
}

}  // namespace snh
