#include "snh/fem/contact_term.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/contact/barrier.hpp"
#include "snh/contact/broad_phase.hpp"
#include "snh/contact/ccd.hpp"
#include "snh/contact/distance_type.hpp"
#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/edge_edge_mollifier.hpp"
#include "snh/contact/pair_barrier.hpp"
#include "snh/contact/point_edge_distance.hpp"
#include "snh/contact/point_point_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/contact/project_psd.hpp"

namespace snh {
namespace {

using contact::Derivatives;
using Kind = ContactPair::Kind;

void check_positive(const char* what, double value) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw std::invalid_argument(fmt::format("contact: {} must be finite and > 0, got {:g}", what, value));
}

/// κ w b∘s from the distance's derivatives (s < ŝ; s ≤ 0 gives +∞).
template <int N>
Derivatives<N> weighted_barrier(const Derivatives<N>& s, double s_hat, double scale, bool project) {
  if (!(s.value > 0.0)) {
    Derivatives<N> touching;
    touching.value = std::isnan(s.value) ? std::numeric_limits<double>::quiet_NaN() : std::numeric_limits<double>::infinity();
    return touching;
  }
  Derivatives<N> b = contact::barrier_of(s, s_hat, scale);
  if (project) b.hessian = contact::project_psd(b.hessian);
  return b;
}

/// Adds a pair's energy derivatives (over its `N/3` vertices) to the gradient and the Hessian.
template <int N>
void scatter_direct(const Derivatives<N>& d, const std::array<int, 4>& ids, Eigen::VectorXd* gradient,
                    const HessianValues* hessian) {
  constexpr int M = N / 3;
  if (gradient)
    for (int i = 0; i < M; ++i) gradient->segment<3>(3 * ids[i]) += d.gradient.template segment<3>(3 * i);
  if (hessian)
    for (int i = 0; i < M; ++i)
      for (int j = i; j < M; ++j) hessian->add_block(ids[i], ids[j], d.hessian.template block<3, 3>(3 * i, 3 * j));
}

ContactPair point_point(int v, int w, double s) {
  ContactPair p;
  p.kind = Kind::point_point;
  p.vertices = {std::min(v, w), std::max(v, w), -1, -1};
  p.squared_distance = s;
  return p;
}

ContactPair point_edge(int v, int e0, int e1, double s) {
  ContactPair p;
  p.kind = Kind::point_edge;
  p.vertices = {v, std::min(e0, e1), std::max(e0, e1), -1};
  p.squared_distance = s;
  return p;
}

}  // namespace

ContactTerm::ContactTerm(Eigen::Matrix3Xi F, EmbeddedPoints points, const Eigen::Matrix3Xd& volume_rest, double dhat,
                         double stiffness)
    : F_(std::move(F)), volume_vertices_(volume_rest.cols()), embedded_(!points.is_plain()), dhat_(dhat), kappa_(stiffness) {
  check_positive("dhat", dhat_);
  check_positive("stiffness", kappa_);
  if (!volume_rest.allFinite()) throw std::invalid_argument("contact: the rest positions are not all finite");
  points.check_vertices(volume_vertices_, "contact: surface points");
  number_surface(points.size());
  points_ = points.select(surface_vertices_);  // only the points the triangles use, in the local order
  surface_rest_ = positions(Eigen::Map<const Eigen::VectorXd>(volume_rest.data(), volume_rest.size()));
}

void ContactTerm::number_surface(Eigen::Index id_count) {
  for (Eigen::Index t = 0; t < F_.cols(); ++t) {
    for (int k = 0; k < 3; ++k)
      if (F_(k, t) < 0 || F_(k, t) >= id_count)
        throw std::invalid_argument(
            fmt::format("contact: triangle {} has vertex id {} outside [0, {})", t, F_(k, t), id_count));
    if (F_(0, t) == F_(1, t) || F_(1, t) == F_(2, t) || F_(2, t) == F_(0, t))
      throw std::invalid_argument(fmt::format("contact: triangle {} repeats a vertex", t));
  }
  // The surface's own vertex numbering (ids of F in increasing order), so that the broad phase sees the
  // surface only (a volume mesh's interior vertices never collide) and local order is global order.
  std::vector<int> ids(F_.data(), F_.data() + F_.size());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  surface_vertices_ = ids;
  std::vector<int> local(static_cast<std::size_t>(id_count), -1);
  for (std::size_t i = 0; i < ids.size(); ++i) local[static_cast<std::size_t>(ids[i])] = static_cast<int>(i);
  local_F_ = F_.unaryExpr([&](int v) { return local[static_cast<std::size_t>(v)]; });
  local_E_ = contact::surface_edges(local_F_);
  E_ = local_E_.unaryExpr([&](int v) { return surface_vertices_[static_cast<std::size_t>(v)]; });
}

Eigen::Matrix3Xd ContactTerm::positions(const Eigen::VectorXd& x) const {
  if (x.size() != 3 * volume_vertices_)
    throw std::logic_error(fmt::format("contact: {} DOFs for {} vertices", x.size(), volume_vertices_));
  Eigen::Matrix3Xd V(3, static_cast<Eigen::Index>(surface_vertices_.size()));
  if (!embedded_) {
    for (Eigen::Index i = 0; i < V.cols(); ++i) V.col(i) = x.segment<3>(3 * vertex_of(i));
    return V;
  }
  return points_.points(x);
}

template <int N>
void ContactTerm::scatter(const Derivatives<N>& d, const std::array<int, 4>& ids, Eigen::VectorXd* gradient,
                          const HessianValues* hessian) const {
  constexpr int M = N / 3;
  if (!embedded_) {
    std::array<int, 4> global = ids;
    for (int i = 0; i < M; ++i) global[i] = vertex_of(ids[i]);
    scatter_direct(d, global, gradient, hessian);
    return;
  }
  points_.scatter(d, ids, gradient, hessian);
}

const std::vector<ContactPair>& ContactTerm::pairs_at(const Eigen::VectorXd& x, const Eigen::Matrix3Xd** P) const {
  if (!(cache_x_.size() == x.size() && cache_x_ == x) || !x.allFinite()) {
    cache_positions_ = positions(x);
    cache_pairs_ = local_pairs(cache_positions_, candidates_near(cache_positions_));
    if (x.allFinite()) cache_x_ = x;
    else cache_x_.resize(0);
  }
  if (P) *P = &cache_positions_;
  return cache_pairs_;
}

std::vector<ContactPair> ContactTerm::pairs(const Eigen::VectorXd& x) const {
  std::vector<ContactPair> merged = pairs_at(x);
  for (ContactPair& p : merged)
    for (int& v : p.vertices)
      if (v >= 0) v = surface_vertices_[static_cast<std::size_t>(v)];
  return merged;
}

int ContactTerm::active_pairs(const Eigen::VectorXd& x) const {
  if (!x.allFinite()) return 0;
  return static_cast<int>(pairs_at(x).size());
}

const contact::Candidates& ContactTerm::candidates_near(const Eigen::Matrix3Xd& V) const {
  if (!(candidates_at_.cols() == V.cols() && (V - candidates_at_).cwiseAbs().maxCoeff() <= 0.5 * dhat_)) {
    candidates_ = contact::broad_phase(V, V, local_F_, local_E_, 2.0 * dhat_);  // boxes grown by d̂
    candidates_at_ = V;
  }
  return candidates_;
}

std::vector<ContactPair> ContactTerm::local_pairs(const Eigen::Matrix3Xd& V, const contact::Candidates& c) const {
  const double s_hat = dhat_ * dhat_;
  std::vector<ContactPair> raw;  // in local vertex ids (same order as the global ones)
  for (const auto& [v, t] : c.vertex_triangle) {
    const int a = local_F_(0, t), b = local_F_(1, t), d = local_F_(2, t);
    const Vec3 p = V.col(v), t0 = V.col(a), t1 = V.col(b), t2 = V.col(d);
    const contact::PointTriangleType type = contact::point_triangle_distance_type(p, t0, t1, t2);
    const double s = contact::point_triangle_distance(p, t0, t1, t2, type);
    if (!(s < s_hat)) continue;
    using T = contact::PointTriangleType;
    switch (type) {
      case T::p_t0: raw.push_back(point_point(v, a, s)); break;
      case T::p_t1: raw.push_back(point_point(v, b, s)); break;
      case T::p_t2: raw.push_back(point_point(v, d, s)); break;
      case T::p_e0: raw.push_back(point_edge(v, a, b, s)); break;
      case T::p_e1: raw.push_back(point_edge(v, b, d, s)); break;
      case T::p_e2: raw.push_back(point_edge(v, d, a, s)); break;
      case T::p_t: {
        ContactPair pt;
        pt.kind = Kind::point_triangle;
        pt.vertices = {v, a, b, d};
        pt.squared_distance = s;
        raw.push_back(pt);
        break;
      }
    }
  }
  for (const auto& [ea, eb] : c.edge_edge) {
    const int a0 = local_E_(0, ea), a1 = local_E_(1, ea), b0 = local_E_(0, eb), b1 = local_E_(1, eb);
    const Vec3 pa0 = V.col(a0), pa1 = V.col(a1), pb0 = V.col(b0), pb1 = V.col(b1);
    const contact::EdgeEdgeType type = contact::edge_edge_distance_type(pa0, pa1, pb0, pb1);
    const double s = contact::edge_edge_distance(pa0, pa1, pb0, pb1, type);
    if (!(s < s_hat)) continue;
    const auto rest = [&](int v) { return Vec3(surface_rest_.col(v)); };
    const double eps = contact::edge_edge_mollifier_threshold(rest(a0), rest(a1), rest(b0), rest(b1));
    const double cross = (pa1 - pa0).cross(pb1 - pb0).squaredNorm();
    using T = contact::EdgeEdgeType;
    if (cross < eps || type == T::ea_eb) {
      ContactPair ee;
      ee.kind = Kind::edge_edge;
      ee.vertices = {a0, a1, b0, b1};
      ee.squared_distance = s;
      ee.mollifier_threshold = eps;
      raw.push_back(ee);
      continue;
    }
    switch (type) {
      case T::ea0_eb0: raw.push_back(point_point(a0, b0, s)); break;
      case T::ea0_eb1: raw.push_back(point_point(a0, b1, s)); break;
      case T::ea1_eb0: raw.push_back(point_point(a1, b0, s)); break;
      case T::ea1_eb1: raw.push_back(point_point(a1, b1, s)); break;
      case T::ea_eb0: raw.push_back(point_edge(b0, a0, a1, s)); break;
      case T::ea_eb1: raw.push_back(point_edge(b1, a0, a1, s)); break;
      case T::ea0_eb: raw.push_back(point_edge(a0, b0, b1, s)); break;
      case T::ea1_eb: raw.push_back(point_edge(a1, b0, b1, s)); break;
      case T::ea_eb: break;  // handled above
    }
  }
  // Merge by key (kind, vertex ids): sorted, so the result and the order of the sums are deterministic.
  const auto key_less = [](const ContactPair& p, const ContactPair& q) {
    return std::tie(p.kind, p.vertices) < std::tie(q.kind, q.vertices);
  };
  std::sort(raw.begin(), raw.end(), key_less);
  std::vector<ContactPair> merged;
  for (ContactPair& p : raw) {
    if (!merged.empty() && merged.back().kind == p.kind && merged.back().vertices == p.vertices) {
      ++merged.back().weight;
      continue;
    }
    p.weight = 1;
    merged.push_back(p);
  }
  return merged;
}

double ContactTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double ContactTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                             PsdProjection projection) const {
  const ScopeTimer timed(counters_.seconds);
  if (!x.allFinite()) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix3Xd* P = nullptr;
  const std::vector<ContactPair>& pairs = pairs_at(x, &P);
  const Eigen::Matrix3Xd& V = *P;
  const double s_hat = dhat_ * dhat_;
  const bool project = projection != PsdProjection::none;
  double e = 0.0;
  for (const ContactPair& p : pairs) {
    const double scale = kappa_ * p.weight;
    const auto& id = p.vertices;
    // Scatters a pair's derivatives (where its energy is finite) and gives its energy.
    const auto add = [&](const auto& d) {
      if (std::isfinite(d.value)) scatter(d, id, gradient, hessian);
      return d.value;
    };
    double value = 0.0;
    switch (p.kind) {
      case Kind::point_point:
        value = add(weighted_barrier(contact::point_point_distance_derivatives(V.col(id[0]), V.col(id[1])), s_hat, scale,
                                     project));
        break;
      case Kind::point_edge:
        value = add(weighted_barrier(contact::point_edge_distance_derivatives(V.col(id[0]), V.col(id[1]), V.col(id[2]),
                                                                              contact::PointEdgeType::p_e),
                                     s_hat, scale, project));
        break;
      case Kind::point_triangle:
        value = add(weighted_barrier(contact::point_triangle_distance_derivatives(V.col(id[0]), V.col(id[1]), V.col(id[2]),
                                                                                  V.col(id[3]), contact::PointTriangleType::p_t),
                                     s_hat, scale, project));
        break;
      case Kind::edge_edge: {
        Derivatives<12> d = contact::edge_edge_barrier(V.col(id[0]), V.col(id[1]), V.col(id[2]), V.col(id[3]), s_hat,
                                                       p.mollifier_threshold, project);
        d.value *= scale;
        d.gradient *= scale;
        d.hessian *= scale;
        value = add(d);
        break;
      }
    }
    if (!std::isfinite(value)) return value;  // in contact (+∞) or undefined (NaN)
    e += value;
  }
  return e;
}

void ContactTerm::stencil(const Eigen::VectorXd& x, Stencil& out) const {
  const ScopeTimer timed(counters_.seconds);
  out.arity = 2;
  out.vertices.clear();
  if (!x.allFinite()) return;
  if (!embedded_) {
    for (const ContactPair& p : pairs_at(x))
      for (int i = 0; i < p.arity(); ++i)
        for (int j = i + 1; j < p.arity(); ++j) out.vertices.insert(out.vertices.end(), {vertex_of(p.vertices[i]), vertex_of(p.vertices[j])});
    return;
  }
  for (const ContactPair& p : pairs_at(x)) points_.couple(p.vertices, p.arity(), out.vertices);
}

void ContactTerm::stencil_ahead(const Eigen::VectorXd& x, Stencil& out) const {
  const ScopeTimer timed(counters_.seconds);
  out.arity = 2;
  out.vertices.clear();
  if (!x.allFinite()) return;
  const Eigen::Matrix3Xd V = positions(x);
  const double reach = layout_reach();
  const contact::Candidates c = contact::broad_phase(V, V, local_F_, local_E_, reach);
  const double r2 = reach * reach;
  const auto couple = [&](const std::array<int, 4>& ids) {
    if (embedded_) {
      points_.couple(ids, 4, out.vertices);
      return;
    }
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) out.vertices.insert(out.vertices.end(), {vertex_of(ids[i]), vertex_of(ids[j])});
  };
  for (const auto& [v, t] : c.vertex_triangle) {
    const std::array<int, 4> ids{v, local_F_(0, t), local_F_(1, t), local_F_(2, t)};
    if (contact::point_triangle_distance(V.col(ids[0]), V.col(ids[1]), V.col(ids[2]), V.col(ids[3])) < r2) couple(ids);
  }
  for (const auto& [ea, eb] : c.edge_edge) {
    const std::array<int, 4> ids{local_E_(0, ea), local_E_(1, ea), local_E_(0, eb), local_E_(1, eb)};
    if (contact::edge_edge_distance(V.col(ids[0]), V.col(ids[1]), V.col(ids[2]), V.col(ids[3])) < r2) couple(ids);
  }
}

Crowding ContactTerm::crowding(const Eigen::VectorXd& x, std::size_t max_candidates) const {
  const Eigen::Matrix3Xd V = positions(x);
  const contact::Candidates c = contact::broad_phase(V, V, local_F_, local_E_, dhat_, max_candidates);
  Crowding out;
  out.complete = c.complete;
  out.candidates = c.vertex_triangle.size() + c.edge_edge.size();
  out.vertices = V.cols();
  out.min_distance = dhat_;
  for (Eigen::Index e = 0; e < local_E_.cols(); ++e) out.mean_edge += (V.col(local_E_(0, e)) - V.col(local_E_(1, e))).norm();
  if (local_E_.cols() > 0) out.mean_edge /= static_cast<double>(local_E_.cols());
  if (!c.complete) return out;
  const std::vector<ContactPair> pairs = local_pairs(V, c);
  std::vector<bool> in(static_cast<std::size_t>(V.cols()), false);
  for (const ContactPair& p : pairs) {
    for (int i = 0; i < p.arity(); ++i) in[static_cast<std::size_t>(p.vertices[i])] = true;
    out.min_distance = std::min(out.min_distance, std::sqrt(std::max(p.squared_distance, 0.0)));
  }
  out.pairs = pairs.size();
  out.in_range = static_cast<Eigen::Index>(std::count(in.begin(), in.end(), true));
  return out;
}

double ContactTerm::min_distance(const Eigen::VectorXd& x) const {
  double s = dhat_ * dhat_;
  for (const ContactPair& p : pairs(x)) s = std::min(s, p.squared_distance);
  return std::sqrt(std::max(s, 0.0));
}

double ContactTerm::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
  const ScopeTimer timed(counters_.seconds);
  ++counters_.ccd_calls;
  if (!x.allFinite() || !dx.allFinite()) return 1.0;  // the line search rejects what follows
  const Eigen::Matrix3Xd V0 = positions(x), D = positions(dx);  // D = W dx: the points move linearly too
  const Eigen::Matrix3Xd V1 = V0 + D;
  const contact::Candidates c = contact::broad_phase(V0, V1, local_F_, local_E_, dhat_);  // pairs within d̂: contact_term.hpp
  counters_.ccd_tests += static_cast<long long>(c.vertex_triangle.size() + c.edge_edge.size());
  double t = 1.0;
  for (const auto& [v, f] : c.vertex_triangle) {
    const int a = local_F_(0, f), b = local_F_(1, f), d = local_F_(2, f);
    t = std::min(t, contact::point_triangle_ccd(V0.col(v), V0.col(a), V0.col(b), V0.col(d), D.col(v), D.col(a),
                                                D.col(b), D.col(d)));
  }
  for (const auto& [ea, eb] : c.edge_edge) {
    const int a0 = local_E_(0, ea), a1 = local_E_(1, ea), b0 = local_E_(0, eb), b1 = local_E_(1, eb);
    t = std::min(t, contact::edge_edge_ccd(V0.col(a0), V0.col(a1), V0.col(b0), V0.col(b1), D.col(a0), D.col(a1),
                                           D.col(b0), D.col(b1)));
  }
  return t;
}

double ipc_barrier_stiffness(double bbox_diagonal, double dhat, double average_mass, double dt) {
  check_positive("the bounding box diagonal", bbox_diagonal);
  check_positive("dhat", dhat);
  check_positive("the average vertex mass", average_mass);
  check_positive("the time step", dt);
  double d0 = 1e-8 * bbox_diagonal;
  d0 *= d0;
  const double s_hat = dhat * dhat;
  if (!(d0 < s_hat)) d0 = 0.5 * s_hat;  // a d̂ below 1e-8 of the scene: the barrier's own middle
  const double scaled = 1e11 * average_mass / (4.0 * d0 * contact::barrier_second_derivative(d0, s_hat));
  return scaled / (dt * dt);
}

}  // namespace snh
