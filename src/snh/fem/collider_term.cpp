#include "snh/fem/collider_term.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
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
  F_ = F.unaryExpr([&](int v) { return local[static_cast<std::size_t>(v)]; });
  E_ = contact::surface_edges(F_);
  // The simulated surface at rest: its vertices, or the points W X of the volume at rest.
  rest_ = points_.points(Eigen::Map<const Eigen::VectorXd>(rest.data(), rest.size()));
  // The collider's edges, each triangle's three, the vertices no triangle uses, and the tree over its
  // triangles' boxes in the base frame (built once: the pose moves the collider as a whole).
  collider_E_ = contact::surface_edges(T, &triangle_edges_);
  std::vector<char> used(static_cast<std::size_t>(base_.cols()), 0);
  Eigen::Matrix3Xd lo(3, T.cols()), hi(3, T.cols());
  for (Eigen::Index t = 0; t < T.cols(); ++t) {
    lo.col(t) = hi.col(t) = base_.col(T(0, t));
    for (int k = 0; k < 3; ++k) {
      used[static_cast<std::size_t>(T(k, t))] = 1;
      lo.col(t) = lo.col(t).cwiseMin(base_.col(T(k, t)));
      hi.col(t) = hi.col(t).cwiseMax(base_.col(T(k, t)));
    }
  }
  for (int v = 0; v < static_cast<int>(base_.cols()); ++v)
    if (!used[static_cast<std::size_t>(v)]) loose_.push_back(v);
  tree_ = contact::BoxTree(lo, hi);
  placed_ = placed_at(0.0);
  if (pose_) pose_now_ = pose_(0.0);
}

Eigen::Matrix3Xd MeshColliderTerm::placed_at(double t) const {
  if (!pose_) return base_;
  const Eigen::Affine3d A = pose_(t);
  Eigen::Matrix3Xd P = (A.linear() * base_).colwise() + A.translation();
  if (!P.allFinite()) throw std::invalid_argument(fmt::format("collider: the mesh's pose at t = {:g} is not finite", t));
  return P;
}

void MeshColliderTerm::at_time(double t) {
  placed_ = placed_at(t);
  if (pose_) pose_now_ = pose_(t);
}

Eigen::Matrix3Xd MeshColliderTerm::surface_at(const Eigen::VectorXd& x) const {
  if (x.size() != 3 * volume_vertices_)
    throw std::logic_error(fmt::format("collider: {} DOFs for {} vertices", x.size(), volume_vertices_));
  return points_.points(x);  // plain vertices: their coordinates, bit for bit
}

std::vector<int> MeshColliderTerm::triangles_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const {
  // The box's corners taken to the base frame by the inverse pose, and the box of those, a little larger
  // (the exact test in world coordinates follows, so only missing a triangle to rounding would matter).
  if (!pose_) return tree_.near(lo, hi);
  if (std::abs(pose_now_.linear().determinant()) > 0.0) {
    const Eigen::Affine3d inverse = pose_now_.inverse(Eigen::Affine);
    Eigen::Vector3d a = Eigen::Vector3d::Constant(inf), b = -a;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d c((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(), (corner & 4) ? hi.z() : lo.z());
      const Eigen::Vector3d q = inverse * c;
      a = a.cwiseMin(q);
      b = b.cwiseMax(q);
    }
    const double slack = 1e-9 * ((b - a).norm() + std::max(a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()));
    if (a.allFinite() && b.allFinite()) return tree_.near(a.array() - slack, b.array() + slack);
  }
  return all_triangles();  // a pose that cannot be inverted
}

std::vector<int> MeshColliderTerm::all_triangles() const {
  std::vector<int> all(static_cast<std::size_t>(collider_T_.cols()));
  std::iota(all.begin(), all.end(), 0);
  return all;
}

MeshColliderTerm::Near MeshColliderTerm::near(const Eigen::Matrix3Xd& S, const Eigen::Matrix3Xd* DS, const Eigen::Matrix3Xd& C,
                                              const Eigen::Matrix3Xd* DC, bool indexed, double dhat) const {
  Near out;
  const auto ns = static_cast<int>(S.cols());
  if (ns == 0) return out;
  // Only the collider's primitives near the body can pair with it: those whose boxes over the step come
  // within d̂ of the body's box over the step (pairs of two of the collider's own are never asked). The
  // collider's tree finds its triangles that may be near (a triangle's box holds its edges' and vertices'),
  // each is tested exactly, and the broad phase runs on the body and what of the collider is near: a cost in
  // proportion to that, not to the collider's size (a 20 000-triangle collider 4 m away made a 0.16 s run
  // take 38 s, and 2 million triangles 53 s with a linear scan of them at every call). The candidates are
  // those of a broad phase over both whole surfaces, in the same order.
  const Eigen::Matrix3Xd S1 = DS ? Eigen::Matrix3Xd(S + *DS) : S;
  const Eigen::Vector3d lo = S.rowwise().minCoeff().cwiseMin(S1.rowwise().minCoeff()).array() - dhat;
  const Eigen::Vector3d hi = S.rowwise().maxCoeff().cwiseMax(S1.rowwise().maxCoeff()).array() + dhat;
  const auto end_of = [&](int v) { return DC ? Eigen::Vector3d(C.col(v) + DC->col(v)) : Eigen::Vector3d(C.col(v)); };
  const auto is_near = [&](const auto& ids) {
    Eigen::Vector3d a = C.col(ids[0]), b = a;
    for (Eigen::Index k = 0; k < ids.size(); ++k) {
      const Eigen::Vector3d p1 = end_of(ids[k]);
      a = a.cwiseMin(C.col(ids[k])).cwiseMin(p1);
      b = b.cwiseMax(C.col(ids[k])).cwiseMax(p1);
    }
    return (a.array() <= hi.array()).all() && (b.array() >= lo.array()).all();
  };
  const std::vector<int> triangles = indexed ? triangles_near(lo, hi) : all_triangles();
  std::vector<int> kept_triangles, edges, vertices;  // the collider's near primitives, ascending
  for (const int t : triangles)
    if (is_near(collider_T_.col(t))) {
      kept_triangles.push_back(t);
      for (int k = 0; k < 3; ++k) edges.push_back(triangle_edges_(k, t)), vertices.push_back(collider_T_(k, t));
    }
  for (const int v : loose_)
    if (is_near(Eigen::Matrix<int, 1, 1>(v))) vertices.push_back(v);
  const auto sort_unique = [](std::vector<int>& ids) {
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  };
  sort_unique(edges);
  sort_unique(vertices);
  std::vector<int> kept_edges;
  for (const int e : edges)
    if (is_near(collider_E_.col(e))) kept_edges.push_back(e);
  if (vertices.empty()) return out;  // nothing of the collider near: no pair
  // The compact surfaces: the body's vertices, then the collider's near ones.
  const auto nc = static_cast<Eigen::Index>(vertices.size());
  const auto compact = [&](int v) {
    return ns + static_cast<int>(std::lower_bound(vertices.begin(), vertices.end(), v) - vertices.begin());
  };
  out.V.resize(3, ns + nc);
  out.V.leftCols(ns) = S;
  Eigen::Matrix3Xd W1(3, ns + nc);
  W1.leftCols(ns) = S1;
  if (DS || DC) out.D.resize(3, ns + nc);
  if (DS) out.D.leftCols(ns) = *DS;
  else if (DC) out.D.leftCols(ns).setZero();
  for (Eigen::Index i = 0; i < nc; ++i) {
    const int v = vertices[static_cast<std::size_t>(i)];
    out.V.col(ns + i) = C.col(v);
    W1.col(ns + i) = end_of(v);
    if (DC) out.D.col(ns + i) = DC->col(v);
    else if (DS) out.D.col(ns + i).setZero();
  }
  Eigen::Matrix3Xi F(3, F_.cols() + static_cast<Eigen::Index>(kept_triangles.size()));
  F.leftCols(F_.cols()) = F_;
  for (std::size_t i = 0; i < kept_triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) F(k, F_.cols() + static_cast<Eigen::Index>(i)) = compact(collider_T_(k, kept_triangles[i]));
  Eigen::Matrix2Xi E(2, E_.cols() + static_cast<Eigen::Index>(kept_edges.size()));
  E.leftCols(E_.cols()) = E_;
  for (std::size_t i = 0; i < kept_edges.size(); ++i)
    for (int k = 0; k < 2; ++k) E(k, E_.cols() + static_cast<Eigen::Index>(i)) = compact(collider_E_(k, kept_edges[i]));
  const contact::Candidates c = contact::broad_phase(out.V, W1, F, E, dhat);
  const auto rest_of = [&](int id) {  // the simulated points at rest; the collider in its base frame
    return id < ns ? Eigen::Vector3d(rest_.col(id)) : Eigen::Vector3d(base_.col(vertices[static_cast<std::size_t>(id - ns)]));
  };
  for (const auto& [v, t] : c.vertex_triangle)
    if ((v < ns) != (t < triangles_simulated_)) out.pairs.push_back({false, {v, F(0, t), F(1, t), F(2, t)}, 0.0});
  for (const auto& [a, b] : c.edge_edge) {
    if ((E(0, a) < ns) == (E(0, b) < ns)) continue;  // both edges of one body
    const std::array<int, 4> id{E(0, a), E(1, a), E(0, b), E(1, b)};
    out.pairs.push_back({true, id, contact::edge_edge_mollifier_threshold(rest_of(id[0]), rest_of(id[1]), rest_of(id[2]), rest_of(id[3]))});
  }
  return out;
}

double MeshColliderTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double MeshColliderTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                                  PsdProjection projection) const {
  const ScopeTimer timed(counters_.seconds);
  if (!x.allFinite()) return nan;
  const Near n = near(surface_at(x), nullptr, placed_, nullptr, true, dhat_);
  const Eigen::Matrix3Xd& V = n.V;
  const auto ns = static_cast<int>(surface_vertices_.size());
  const double s_hat = dhat_ * dhat_;
  const bool project = projection != PsdProjection::none;
  double e = 0.0;
  for (const Candidate& c : n.pairs) {
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
  const auto ns = static_cast<int>(surface_vertices_.size());
  for (const Candidate& c : near(surface_at(x), nullptr, placed_, nullptr, true, dhat_).pairs) {
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
  const Near n = near(surface_at(x), nullptr, placed_, nullptr, true, dhat_);
  const Eigen::Matrix3Xd& V = n.V;
  std::vector<double> out;
  for (const Candidate& c : n.pairs) {
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

double MeshColliderTerm::ccd(const Near& n, long long* tested) const {
  double t = 1.0;
  // Pairs within d̂ (boxes grown by d̂/2 each), as ContactTerm::max_step: a pair ending in touching is not lost to the boxes' rounding.
  const Eigen::Matrix3Xd &V0 = n.V, &D = n.D;
  if (tested) *tested += static_cast<long long>(n.pairs.size());
  for (const Candidate& c : n.pairs) {
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
  const Eigen::Matrix3Xd D = surface_at(dx);  // the collider holds still
  return ccd(near(surface_at(x), &D, placed_, nullptr, true, dhat_), &counters_.ccd_tests);
}

double MeshColliderTerm::sweep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double t0, double t1) const {
  if (!pose_ || !x.allFinite() || !dx.allFinite()) return 1.0;
  // The collider moves over the frame: every triangle is tested (once a frame), not the tree at one pose.
  const Eigen::Matrix3Xd P0 = placed_at(t0), P1 = placed_at(t1), DC = P1 - P0, D = surface_at(dx);
  return ccd(near(surface_at(x), &D, P0, &DC, false, dhat_));
}

}  // namespace snh
