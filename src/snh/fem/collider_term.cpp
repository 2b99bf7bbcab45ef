#include "snh/fem/collider_term.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/contact/barrier.hpp"
#include "snh/contact/broad_phase.hpp"
#include "snh/contact/ccd.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"
#include "snh/contact/pair_barrier.hpp"
#include "snh/contact/point_triangle_distance.hpp"

namespace snh {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();

void require_positive(const char* what, double value) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw std::invalid_argument(fmt::format("collider: {} must be finite and > 0, got {:g}", what, value));
}

}  // namespace

ShapeDistance shape_distance(const ColliderShape& shape, const Vec3& q, bool hessian) {
  ShapeDistance out;
  if (shape.kind == ColliderShape::Kind::plane) {  // signed distance, linear
    out.distance = shape.b.dot(q - shape.a);
    out.normal = shape.b;
    return out;
  }
  // The closest point c of the core and the projector P = I − J on the directions c does not follow.
  Vec3 c = shape.a;
  Mat3 P = Mat3::Identity();
  if (shape.kind == ColliderShape::Kind::capsule) {
    const Vec3 axis = shape.b - shape.a;
    const double length2 = axis.squaredNorm();
    const double tau = length2 > 0.0 ? (q - shape.a).dot(axis) / length2 : 0.0;
    if (tau > 0.0 && tau < 1.0) {
      c = shape.a + tau * axis;
      P -= axis * axis.transpose() / length2;
    } else {
      c = tau <= 0.0 ? shape.a : shape.b;
    }
  } else if (shape.kind == ColliderShape::Kind::box) {
    const Vec3 lo = shape.a - shape.b, hi = shape.a + shape.b;
    for (int i = 0; i < 3; ++i) {
      c[i] = std::clamp(q[i], lo[i], hi[i]);
      if (c[i] == q[i]) P(i, i) = 0.0;  // inside the slab: c follows q along this axis
    }
  }
  const Vec3 u = q - c;
  const double r = u.norm();
  if (!(r > 0.0)) {  // on the core (inside the shape), or not finite
    out.distance = std::isnan(r) ? nan : -shape.radius;
    return out;
  }
  out.normal = u / r;
  out.distance = r - shape.radius;
  if (hessian) out.hessian = (P - out.normal * out.normal.transpose()) / r;
  return out;
}

double shape_step(const ColliderShape& shape, const Vec3& q, const Vec3& dq, double keep) {
  const double d0 = shape_distance(shape, q).distance;
  if (!(d0 > 0.0)) return 0.0;
  const double floor = keep * d0;
  double tau = 0.0;
  for (int it = 0; it < 200; ++it) {
    const ShapeDistance sd = shape_distance(shape, q + tau * dq);
    const double slope = sd.normal.dot(dq);
    if (!(slope < 0.0)) return 1.0;  // not approaching: d is convex along the line, it only grows from here
    // The tangent's root of d = floor: at or before the true one (convexity).
    const double next = tau + (sd.distance - floor) / -slope;
    if (!(next < 1.0)) return 1.0;
    // Rounding may put d at the tangent's root a hair below floor: accept half of it, never less.
    if (!(shape_distance(shape, q + next * dq).distance > 0.5 * floor) || next - tau <= 1e-12) return tau;
    tau = next;
  }
  return tau;
}

// ---------------------------------------------------------------------------------------------------------

ShapeColliderTerm::ShapeColliderTerm(EmbeddedPoints points, ColliderShape shape, ColliderPose pose, double dhat, double stiffness)
    : points_(std::move(points)),
      embedded_(!points_.is_plain()),
      shape_(std::move(shape)),
      pose_(std::move(pose)),
      dhat_(dhat),
      kappa_(stiffness) {
  require_positive("dhat", dhat_);
  require_positive("stiffness", kappa_);
  if (!shape_.a.allFinite() || !shape_.b.allFinite() || !std::isfinite(shape_.radius))
    throw std::invalid_argument("collider: the shape's numbers are not all finite");
  using K = ColliderShape::Kind;
  if (shape_.kind == K::plane) {
    if (!(shape_.b.norm() > 0.0)) throw std::invalid_argument("collider: the plane's normal must be non-zero");
    shape_.b.normalize();
    shape_.radius = 0.0;
  }
  if ((shape_.kind == K::sphere || shape_.kind == K::capsule) && !(shape_.radius > 0.0))
    throw std::invalid_argument(fmt::format("collider: the radius must be > 0, got {:g}", shape_.radius));
  if (shape_.kind == K::box) {
    if (!(shape_.b.minCoeff() > 0.0)) throw std::invalid_argument("collider: the box's half extents must be > 0");
    shape_.radius = 0.0;
  }
  frame_ = frame_at(0.0);
}

ColliderFrame collider_frame(const ColliderPose& pose, double t) {
  ColliderFrame f;
  if (!pose) return f;
  const Eigen::Affine3d A = pose(t);
  const Mat3 L = A.linear();
  f.scale = L.col(0).norm();
  if (!(f.scale > 0.0) || !std::isfinite(f.scale) || !A.translation().allFinite() ||
      !((L.transpose() * L - f.scale * f.scale * Mat3::Identity()).norm() <= 1e-9 * f.scale * f.scale) || !(L.determinant() > 0.0))
    throw std::invalid_argument(
        fmt::format("collider: its pose at t = {:g} is not a rotation, translation and uniform scale", t));
  f.rotation = L / f.scale;
  f.translation = A.translation();
  return f;
}

void ShapeColliderTerm::at_time(double t) { frame_ = frame_at(t); }

double ShapeColliderTerm::point_distance(const Eigen::VectorXd& x, Eigen::Index i) const {
  return frame_.scale * shape_distance(shape_, frame_.to_base(points_.point(x, i))).distance;
}

double ShapeColliderTerm::min_distance(const Eigen::VectorXd& x) const {
  double d = inf;
  for (Eigen::Index i = 0; i < points_.size(); ++i) d = std::min(d, point_distance(x, i));
  return d;
}

int ShapeColliderTerm::active_pairs(const Eigen::VectorXd& x) const {
  int n = 0;
  for (Eigen::Index i = 0; i < points_.size(); ++i)
    if (point_distance(x, i) < dhat_) ++n;
  return n;
}

double ShapeColliderTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double ShapeColliderTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                                   PsdProjection projection) const {
  const ScopeTimer timed(counters_.seconds);
  const double s_hat = dhat_ * dhat_;
  const Mat3& R = frame_.rotation;
  double e = 0.0;
  for (Eigen::Index i = 0; i < points_.size(); ++i) {
    const ShapeDistance sd = shape_distance(shape_, frame_.to_base(points_.point(x, i)), hessian != nullptr);
    const double d = frame_.scale * sd.distance;
    if (std::isnan(d)) return nan;
    if (d <= 0.0) return inf;
    const double s = d * d;
    if (!(s < s_hat)) continue;
    const double b1 = contact::barrier_first_derivative(s, s_hat);
    const Vec3 n = R * sd.normal;  // ∇d in world space
    contact::Derivatives<3> point;  // over the point p
    point.value = kappa_ * contact::barrier(s, s_hat);
    e += point.value;
    point.gradient = (kappa_ * b1 * 2.0 * d) * n;
    if (hessian) {
      const double c = kappa_ * (4.0 * s * contact::barrier_second_derivative(s, s_hat) + 2.0 * b1);
      if (projection != PsdProjection::none) {  // the exact projection (header)
        point.hessian = std::max(c, 0.0) * n * n.transpose();
      } else {
        // ∇²d in world space: R (∇²d in the base frame) Rᵀ / scale.
        const Mat3 Hd = R * sd.hessian * R.transpose() / frame_.scale;
        point.hessian = c * n * n.transpose() + (kappa_ * 2.0 * d * b1) * Hd;
      }
    }
    if (embedded_) {  // through the weights (embedded_points.hpp)
      points_.scatter(point, {static_cast<int>(i), -1, -1, -1}, gradient, hessian);
      continue;
    }
    const int v = points_.vertex()(0, i);
    if (gradient) gradient->segment<3>(3 * v) += point.gradient;
    if (hessian) hessian->add_block(v, v, point.hessian);
  }
  return e;
}

void ShapeColliderTerm::stencil(const Eigen::VectorXd& /*x*/, Stencil& out) const {
  out.vertices.clear();
  out.arity = 0;
  if (!embedded_ || points_.arity() < 2) return;  // plain vertices: a diagonal Hessian
  out.arity = static_cast<int>(points_.arity());    // each point's cell
  out.vertices.assign(points_.vertex().data(), points_.vertex().data() + points_.vertex().size());
}

double ShapeColliderTerm::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  const ScopeTimer timed(counters_.seconds);
  ++counters_.ccd_calls;
  if (!x.allFinite() || !dx.allFinite()) return 1.0;  // the line search rejects what follows
  counters_.ccd_tests += points_.size();
  double t = 1.0;
  for (Eigen::Index i = 0; i < points_.size(); ++i) {
    if (shape_.kind == ColliderShape::Kind::plane) {  // d linear along the step: the root of d = d₀/10 exactly
      // d + τ·(−approach) ≥ d/10  ⇔  τ ≤ 0.9 d / approach (the world normal R n: d's rate along the step)
      const double d = point_distance(x, i), approach = -(frame_.rotation * shape_.b).dot(points_.point(dx, i));
      if (d > 0.0 && approach > 0.0) t = std::min(t, 0.9 * d / approach);
      continue;
    }
    const Vec3 q = frame_.to_base(points_.point(x, i));
    const Vec3 dq = frame_.rotation.transpose() * points_.point(dx, i) / frame_.scale;  // the point moves by W dx
    if (dq == Vec3::Zero()) continue;
    t = std::min(t, shape_step(shape_, q, dq));
  }
  return t;
}

double ShapeColliderTerm::sweep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double t0, double t1) const {
  if (!pose_) return 1.0;
  const Frame f0 = frame_at(t0), f1 = frame_at(t1);
  double t = 1.0;
  for (Eigen::Index i = 0; i < points_.size(); ++i) {
    const Vec3 p = points_.point(x, i);
    const Vec3 q0 = f0.to_base(p), q1 = f1.to_base(p + points_.point(dx, i));
    // Not clear (a tenth): the part that keeps a fifth, so that the shortened part's own sweep, whose poses
    // lie off this chord, is clear with room rather than a hair short of it again and again.
    if (const double clear = shape_step(shape_, q0, q1 - q0); clear < 1.0) t = std::min(t, shape_step(shape_, q0, q1 - q0, 0.2));
  }
  return t;
}

// ---------------------------------------------------------------------------------------------------------

MeshColliderTerm::MeshColliderTerm(const Eigen::Matrix3Xi& F, EmbeddedPoints all, const Eigen::Matrix3Xd& rest, Eigen::Matrix3Xd V,
                                   const Eigen::Matrix3Xi& T, ColliderPose pose, double dhat, double stiffness)
    : embedded_(!all.is_plain()), volume_vertices_(rest.cols()), base_(std::move(V)), collider_T_(T), pose_(std::move(pose)),
      dhat_(dhat), kappa_(stiffness) {
  require_positive("dhat", dhat_);
  require_positive("stiffness", kappa_);
  if (!rest.allFinite() || !base_.allFinite()) throw std::invalid_argument("collider: positions are not all finite");
  const auto check = [](const Eigen::Matrix3Xi& tris, Eigen::Index count, const char* what) {
    for (Eigen::Index t = 0; t < tris.cols(); ++t) {
      for (int k = 0; k < 3; ++k)
        if (tris(k, t) < 0 || tris(k, t) >= count)
          throw std::invalid_argument(fmt::format("collider: {} triangle {} has vertex id {} outside [0, {})", what, t, tris(k, t), count));
      if (tris(0, t) == tris(1, t) || tris(1, t) == tris(2, t) || tris(2, t) == tris(0, t))
        throw std::invalid_argument(fmt::format("collider: {} triangle {} repeats a vertex", what, t));
    }
  };
  all.check_vertices(volume_vertices_, "collider: surface points");
  check(F, all.size(), "surface");
  check(T, base_.cols(), "mesh");
  std::vector<int> ids(F.data(), F.data() + F.size());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  surface_vertices_ = std::move(ids);
  points_ = all.select(surface_vertices_);
  const auto ns = static_cast<int>(surface_vertices_.size());
  std::vector<int> local(static_cast<std::size_t>(all.size()), -1);
  for (int i = 0; i < ns; ++i) local[static_cast<std::size_t>(surface_vertices_[static_cast<std::size_t>(i)])] = i;
  triangles_simulated_ = static_cast<int>(F.cols());
  F_.resize(3, F.cols() + T.cols());
  F_.leftCols(F.cols()) = F.unaryExpr([&](int v) { return local[static_cast<std::size_t>(v)]; });
  F_.rightCols(T.cols()) = T.array() + ns;
  E_ = contact::surface_edges(F_);
  // The simulated surface at rest: its vertices, or the points W X of the volume at rest.
  rest_.resize(3, ns + base_.cols());
  rest_.leftCols(ns) = points_.points(Eigen::Map<const Eigen::VectorXd>(rest.data(), rest.size()));
  rest_.rightCols(base_.cols()) = base_;
  placed_ = placed_at(0.0);
}

Eigen::Matrix3Xd MeshColliderTerm::placed_at(double t) const {
  if (!pose_) return base_;
  const Eigen::Affine3d A = pose_(t);
  Eigen::Matrix3Xd P = (A.linear() * base_).colwise() + A.translation();
  if (!P.allFinite()) throw std::invalid_argument(fmt::format("collider: the mesh's pose at t = {:g} is not finite", t));
  return P;
}

void MeshColliderTerm::at_time(double t) { placed_ = placed_at(t); }

Eigen::Matrix3Xd MeshColliderTerm::combined(const Eigen::VectorXd& x, const Eigen::Matrix3Xd& collider) const {
  if (x.size() != 3 * volume_vertices_)
    throw std::logic_error(fmt::format("collider: {} DOFs for {} vertices", x.size(), volume_vertices_));
  const auto ns = static_cast<Eigen::Index>(surface_vertices_.size());
  Eigen::Matrix3Xd V(3, ns + collider.cols());
  V.leftCols(ns) = points_.points(x);  // plain vertices: their coordinates, bit for bit
  V.rightCols(collider.cols()) = collider;
  return V;
}

std::vector<MeshColliderTerm::Candidate> MeshColliderTerm::candidates(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& V1,
                                                                      double dhat) const {
  const auto ns = static_cast<int>(surface_vertices_.size());
  if (ns == 0) return {};
  // Only the collider's primitives near the body can pair with it: those whose boxes over the step come
  // within d̂ of the body's box over the step (pairs of two of the collider's own are never asked). The broad
  // phase then runs on the body and what of the collider is near, at a cost in proportion to that, not to
  // the collider's size (a 20 000-triangle collider 4 m away made a 0.16 s run take 38 s). The candidates
  // are the same: ids are mapped back in order, so the lists keep their sorted order.
  const Eigen::Vector3d lo = V0.leftCols(ns).rowwise().minCoeff().cwiseMin(V1.leftCols(ns).rowwise().minCoeff()).array() - dhat;
  const Eigen::Vector3d hi = V0.leftCols(ns).rowwise().maxCoeff().cwiseMax(V1.leftCols(ns).rowwise().maxCoeff()).array() + dhat;
  const auto near = [&](const auto& ids) {
    Eigen::Vector3d a = V0.col(ids[0]), b = a;
    for (Eigen::Index k = 0; k < ids.size(); ++k) {
      a = a.cwiseMin(V0.col(ids[k])).cwiseMin(V1.col(ids[k]));
      b = b.cwiseMax(V0.col(ids[k])).cwiseMax(V1.col(ids[k]));
    }
    return (a.array() <= hi.array()).all() && (b.array() >= lo.array()).all();
  };
  std::vector<int> vertex_of, triangle_of, edge_of;  // the kept primitives' original ids, ascending
  std::vector<int> local(static_cast<std::size_t>(V0.cols()), -1);
  for (int v = 0; v < ns; ++v) local[static_cast<std::size_t>(v)] = v;
  for (int t = 0; t < static_cast<int>(F_.cols()); ++t)
    if (t < triangles_simulated_ || near(F_.col(t))) triangle_of.push_back(t);
  for (int e = 0; e < static_cast<int>(E_.cols()); ++e)
    if (E_(0, e) < ns || near(E_.col(e))) edge_of.push_back(e);
  std::vector<char> used(static_cast<std::size_t>(V0.cols()), 0);
  for (const int t : triangle_of)
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(F_(k, t))] = 1;
  for (const int e : edge_of)
    for (int k = 0; k < 2; ++k) used[static_cast<std::size_t>(E_(k, e))] = 1;
  for (int v = 0; v < static_cast<int>(V0.cols()); ++v)
    if (v < ns || used[static_cast<std::size_t>(v)] || near(Eigen::Matrix<int, 1, 1>(v))) {
      local[static_cast<std::size_t>(v)] = static_cast<int>(vertex_of.size());
      vertex_of.push_back(v);
    }
  if (static_cast<int>(vertex_of.size()) == ns) return {};  // nothing of the collider near: no pair
  const auto n = static_cast<Eigen::Index>(vertex_of.size());
  Eigen::Matrix3Xd W0(3, n), W1(3, n);
  for (Eigen::Index i = 0; i < n; ++i) W0.col(i) = V0.col(vertex_of[i]), W1.col(i) = V1.col(vertex_of[i]);
  Eigen::Matrix3Xi F(3, static_cast<Eigen::Index>(triangle_of.size()));
  for (Eigen::Index i = 0; i < F.cols(); ++i)
    for (int k = 0; k < 3; ++k) F(k, i) = local[static_cast<std::size_t>(F_(k, triangle_of[i]))];
  Eigen::Matrix2Xi E(2, static_cast<Eigen::Index>(edge_of.size()));
  for (Eigen::Index i = 0; i < E.cols(); ++i)
    for (int k = 0; k < 2; ++k) E(k, i) = local[static_cast<std::size_t>(E_(k, edge_of[i]))];
  const contact::Candidates c = contact::broad_phase(W0, W1, F, E, dhat);
  std::vector<Candidate> out;
  for (const auto& [vl, tl] : c.vertex_triangle) {
    const int v = vertex_of[vl], t = triangle_of[tl];
    if ((v < ns) != (t < triangles_simulated_)) out.push_back({false, {v, F_(0, t), F_(1, t), F_(2, t)}, 0.0});
  }
  for (const auto& [al, bl] : c.edge_edge) {
    const int a = edge_of[al], b = edge_of[bl];
    if ((E_(0, a) < ns) == (E_(0, b) < ns)) continue;  // both edges of one body
    const std::array<int, 4> id{E_(0, a), E_(1, a), E_(0, b), E_(1, b)};
    out.push_back({true, id,
                   contact::edge_edge_mollifier_threshold(rest_.col(id[0]), rest_.col(id[1]), rest_.col(id[2]), rest_.col(id[3]))});
  }
  return out;
}

double MeshColliderTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double MeshColliderTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                                  PsdProjection projection) const {
  const ScopeTimer timed(counters_.seconds);
  if (!x.allFinite()) return nan;
  const Eigen::Matrix3Xd V = combined(x, placed_);
  const auto ns = static_cast<int>(surface_vertices_.size());
  const double s_hat = dhat_ * dhat_;
  const bool project = projection != PsdProjection::none;
  double e = 0.0;
  for (const Candidate& c : candidates(V, V, dhat_)) {
    const auto& id = c.local;
    contact::Derivatives<12> d =
        c.edge_edge ? contact::edge_edge_barrier(V.col(id[0]), V.col(id[1]), V.col(id[2]), V.col(id[3]), s_hat, c.mollifier_threshold, project)
                    : contact::point_triangle_barrier(V.col(id[0]), V.col(id[1]), V.col(id[2]), V.col(id[3]), s_hat, project);
    if (!std::isfinite(d.value)) return d.value;  // in contact (+∞) or undefined (NaN)
    e += kappa_ * d.value;
    if (embedded_) {  // the simulated points' rows only, through their weights (the collider's slots −1)
      d.gradient *= kappa_;
      d.hessian *= kappa_;
      points_.scatter(d, simulated_slots(id), gradient, hessian);
      continue;
    }
    // The simulated vertices' blocks only (the collider's vertices are not DOFs).
    for (int i = 0; i < 4; ++i) {
      if (id[i] >= ns) continue;
      const int gi = points_.vertex()(0, id[i]);
      if (gradient) gradient->segment<3>(3 * gi) += kappa_ * d.gradient.segment<3>(3 * i);
      if (hessian)
        for (int j = i; j < 4; ++j)
          if (id[j] < ns) hessian->add_block(gi, points_.vertex()(0, id[j]), kappa_ * d.hessian.block<3, 3>(3 * i, 3 * j));
    }
  }
  return e;
}

void MeshColliderTerm::stencil(const Eigen::VectorXd& x, Stencil& out) const {
  const ScopeTimer timed(counters_.seconds);
  out.arity = 2;
  out.vertices.clear();
  if (!x.allFinite()) return;
  const Eigen::Matrix3Xd V = combined(x, placed_);
  const auto ns = static_cast<int>(surface_vertices_.size());
  for (const Candidate& c : candidates(V, V, dhat_)) {
    if (embedded_) {  // every volume vertex of the simulated points' cells
      points_.couple(simulated_slots(c.local), 4, out.vertices);
      continue;
    }
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (c.local[i] < ns && c.local[j] < ns)
          out.vertices.insert(out.vertices.end(), {points_.vertex()(0, c.local[i]), points_.vertex()(0, c.local[j])});
  }
}

std::array<int, 4> MeshColliderTerm::simulated_slots(const std::array<int, 4>& local) const {
  std::array<int, 4> out = local;
  for (int& i : out)
    if (i >= static_cast<int>(surface_vertices_.size())) i = -1;
  return out;
}

std::vector<double> MeshColliderTerm::close_distances(const Eigen::VectorXd& x) const {
  const Eigen::Matrix3Xd V = combined(x, placed_);
  std::vector<double> out;
  for (const Candidate& c : candidates(V, V, dhat_)) {
    const auto& id = c.local;
    const double s = c.edge_edge ? contact::edge_edge_distance(V.col(id[0]), V.col(id[1]), V.col(id[2]), V.col(id[3]))
                                 : contact::point_triangle_distance(V.col(id[0]), V.col(id[1]), V.col(id[2]), V.col(id[3]));
    if (s < dhat_ * dhat_) out.push_back(s);
  }
  return out;
}

double MeshColliderTerm::min_distance(const Eigen::VectorXd& x) const {
  double s = dhat_ * dhat_;
  for (const double c : close_distances(x)) s = std::min(s, c);
  return std::sqrt(std::max(s, 0.0));
}

int MeshColliderTerm::active_pairs(const Eigen::VectorXd& x) const {
  return x.allFinite() ? static_cast<int>(close_distances(x).size()) : 0;
}

double MeshColliderTerm::ccd(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& D, long long* tested) const {
  double t = 1.0;
  // Pairs within d̂ (boxes grown by d̂/2 each), as ContactTerm::max_step: a pair ending in touching is not lost to the boxes' rounding.
  const std::vector<Candidate> swept = candidates(V0, V0 + D, dhat_);
  if (tested) *tested += static_cast<long long>(swept.size());
  for (const Candidate& c : swept) {
    const auto& i = c.local;
    t = std::min(t, c.edge_edge ? contact::edge_edge_ccd(V0.col(i[0]), V0.col(i[1]), V0.col(i[2]), V0.col(i[3]), D.col(i[0]),
                                                         D.col(i[1]), D.col(i[2]), D.col(i[3]))
                                : contact::point_triangle_ccd(V0.col(i[0]), V0.col(i[1]), V0.col(i[2]), V0.col(i[3]), D.col(i[0]),
                                                              D.col(i[1]), D.col(i[2]), D.col(i[3])));
  }
  return t;
}

double MeshColliderTerm::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  const ScopeTimer timed(counters_.seconds);
  ++counters_.ccd_calls;
  if (!x.allFinite() || !dx.allFinite()) return 1.0;  // the line search rejects what follows
  const Eigen::Matrix3Xd V0 = combined(x, placed_);
  const Eigen::Matrix3Xd D = combined(dx, Eigen::Matrix3Xd::Zero(3, placed_.cols()));  // the collider holds still
  return ccd(V0, D, &counters_.ccd_tests);
}

double MeshColliderTerm::sweep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double t0, double t1) const {
  if (!pose_ || !x.allFinite() || !dx.allFinite()) return 1.0;
  const Eigen::Matrix3Xd P0 = placed_at(t0), P1 = placed_at(t1);
  return ccd(combined(x, P0), combined(dx, P1 - P0));
}

}  // namespace snh
