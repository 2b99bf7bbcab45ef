#include "snh/setup/contact_setup.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string_view>

#include <fmt/format.h>

#include "snh/contact/edge_edge_distance.hpp"
#include "snh/contact/point_triangle_distance.hpp"
#include "snh/embed/lattice.hpp"
#include "snh/embed/winding_number.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/fem/friction_term.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/sim/kinematics.hpp"

namespace snh {
namespace {

/// The points the triangles F use, ascending, each once.
std::vector<int> used_points(const Eigen::Matrix3Xi& F) {
  std::vector<int> out(F.data(), F.data() + F.size());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::string_view type_name(ColliderSpec::Type t) {
  constexpr std::string_view names[] = {"plane", "sphere", "capsule", "box", "mesh"};
  return names[static_cast<int>(t)];
}

}  // namespace

ContactSurface boundary_contact_surface(const VolumeMesh& mesh) {
  ContactSurface s;
  s.triangles = boundary_triangles(mesh);
  s.points = EmbeddedPoints::every(mesh.vertex_count());
  s.colliding = used_points(s.triangles);
  s.name = "the mesh's surface";
  return s;
}

ContactSurface skin_contact_surface(const Flesh& flesh) {
  EmbeddedSurface skin = contact_surface(flesh);
  ContactSurface s;
  s.triangles = std::move(skin.triangles);
  s.points = EmbeddedPoints(std::move(skin.points.vertex), std::move(skin.points.weight), "contact: render surface",
                            flesh.volume.vertex_count());
  s.colliding = used_points(s.triangles);
  s.name = "the render surface (welded)";
  s.skin = true;
  return s;
}

ColliderPose collider_pose(const ColliderSpec& c) {
  using T = ColliderSpec::Type;
  if (c.motions.empty()) return {};
  const Eigen::Vector3d centroid = c.type == T::mesh      ? Eigen::Vector3d(c.vertices.rowwise().mean())
                                   : c.type == T::capsule ? Eigen::Vector3d(0.5 * (c.a + c.b))
                                                          : c.a;
  return [motions = c.motions, centroid](double t) { return motion_transform(motions, centroid, t); };
}

ColliderShape collider_shape(const ColliderSpec& c) {
  using T = ColliderSpec::Type;
  ColliderShape shape;
  shape.kind = c.type == T::plane     ? ColliderShape::Kind::plane
               : c.type == T::sphere  ? ColliderShape::Kind::sphere
               : c.type == T::capsule ? ColliderShape::Kind::capsule
                                      : ColliderShape::Kind::box;
  shape.a = c.a;
  shape.b = c.b;
  shape.radius = c.radius;
  return shape;
}

ColliderShape plane_shape(const PlaneColliderSpec& p) { return {ColliderShape::Kind::plane, p.point, p.normal, 0.0}; }

std::shared_ptr<ContactTermBase> collider_term(const ColliderSpec& c, const ContactSurface& surface, const Eigen::Matrix3Xd& rest,
                                               double dhat, double stiffness) {
  if (c.type == ColliderSpec::Type::mesh)
    return std::make_shared<MeshColliderTerm>(surface.triangles, surface.points, rest, c.vertices, c.triangles, collider_pose(c), dhat,
                                              stiffness);
  return std::make_shared<ShapeColliderTerm>(surface.points.select(surface.colliding), collider_shape(c), collider_pose(c), dhat,
                                             stiffness);
}

std::vector<std::shared_ptr<Term>> contact_terms(const ContactSpec& spec, const ContactSurface& surface, const Eigen::Matrix3Xd& rest,
                                                 const ContactParameters& p, std::vector<std::shared_ptr<Term>> between) {
  std::vector<std::shared_ptr<Term>> terms;
  const double dhat = p.dhat, kappa = p.stiffness, mu = p.friction;
  const EmbeddedPoints colliding = surface.points.select(surface.colliding);
  // Lagged Coulomb friction against a plane or shape, on the points it keeps out.
  const auto friction = [&](const ColliderShape& shape, ColliderPose pose) {
    return std::make_shared<FrictionTerm>(colliding, shape, std::move(pose), dhat, kappa, mu, p.slip_velocity);
  };
  if (spec.self) {
    auto self = std::make_shared<ContactTerm>(surface.triangles, surface.points, rest, dhat, kappa);
    terms.push_back(self);
    if (mu > 0.0) terms.push_back(std::make_shared<SelfFrictionTerm>(self, surface.points, dhat, kappa, mu, p.slip_velocity));
  }
  for (const PlaneColliderSpec& plane : spec.planes) {
    terms.push_back(std::make_shared<ShapeColliderTerm>(colliding, plane_shape(plane), ColliderPose{}, dhat, kappa));
    if (mu > 0.0) terms.push_back(friction(plane_shape(plane), ColliderPose{}));
  }
  for (std::shared_ptr<Term>& t : between) terms.push_back(std::move(t));
  for (const ColliderSpec& c : spec.colliders) {
    terms.push_back(collider_term(c, surface, rest, dhat, kappa));
    if (mu > 0.0 && c.type != ColliderSpec::Type::mesh) terms.push_back(friction(collider_shape(c), collider_pose(c)));
  }
  return terms;
}

namespace {

/// Whether the shape (in its base frame) meets the triangle (a, b, c), given in that frame: touching counts.
bool shape_meets_triangle(const ColliderShape& s, const Vec3& a, const Vec3& b, const Vec3& c) {
  switch (s.kind) {
    case ColliderShape::Kind::sphere:
      return contact::point_triangle_distance(s.a, a, b, c) <= s.radius * s.radius;
    case ColliderShape::Kind::capsule: {
      const double r2 = s.radius * s.radius;
      if (segment_meets_triangle(s.a, s.b, a, b, c)) return true;
      if (contact::point_triangle_distance(s.a, a, b, c) <= r2 || contact::point_triangle_distance(s.b, a, b, c) <= r2) return true;
      return contact::edge_edge_distance(s.a, s.b, a, b) <= r2 || contact::edge_edge_distance(s.a, s.b, b, c) <= r2 ||
             contact::edge_edge_distance(s.a, s.b, c, a) <= r2;
    }
    case ColliderShape::Kind::box: {  // the box scaled to the cube [−1, 1]³: overlap is kept by the scaling
      const Vec3 inv = s.b.cwiseInverse();
      return triangle_overlaps_cube({inv.cwiseProduct(a - s.a), inv.cwiseProduct(b - s.a), inv.cwiseProduct(c - s.a)}, 1.0);
    }
    case ColliderShape::Kind::plane:
      break;
  }
  return false;
}

/// The centre of a shape and the radius of a sphere holding it (base frame), and its smallest size.
struct ShapeBounds {
  Vec3 centre;
  double radius = 0.0, smallest = 0.0;
  /// The centre placed by the frame f (world).
  [[nodiscard]] Vec3 centre_at(const ColliderFrame& f) const { return f.rotation * (f.scale * centre) + f.translation; }
};
ShapeBounds shape_bounds(const ColliderShape& s) {
  switch (s.kind) {
    case ColliderShape::Kind::sphere:
      return {s.a, s.radius, s.radius};
    case ColliderShape::Kind::capsule:
      return {0.5 * (s.a + s.b), 0.5 * (s.b - s.a).norm() + s.radius, s.radius};
    case ColliderShape::Kind::box:
      return {s.a, s.b.norm(), s.b.minCoeff()};
    case ColliderShape::Kind::plane:
      break;
  }
  return {Vec3::Zero(), 0.0, 0.0};
}

}  // namespace

void check_self_crowding(const ContactTerm& self, const ContactSurface& surface, const Eigen::VectorXd& x0, const std::string& file) {
  const std::size_t limit = kCrowdedCandidates * std::max<std::size_t>(self.primitive_count(), 1);
  const Crowding c = self.crowding(x0, limit);
  const double dhat = self.dhat(), edge = c.mean_edge;
  if (!c.complete)
    throw SceneError(fmt::format("{}: contact.self: dhat {:g} is too large for {}: more than {} pairs of its primitives ({} a "
                                 "primitive) lie within it at the start, so the barrier would act between neighbours everywhere; "
                                 "give a dhat well below its mean edge length {:.3g}",
                                 file, dhat, surface.name, limit, kCrowdedCandidates, edge));
  // (A surface that touches itself is refused as such after this.)
  if (c.min_distance > 0.0 && static_cast<double>(c.in_range) > kCrowdedShare * static_cast<double>(c.vertices))
    throw SceneError(fmt::format("{}: contact.self: dhat {:g} puts {:.0f}% of the vertices of {} ({} of {}) within dhat of parts "
                                 "of the surface they do not share at the start ({} pairs, the closest {:.3g} apart): the barrier "
                                 "would push the surface apart from itself; give a dhat below {:.3g} (half that distance; its "
                                 "mean edge length is {:.3g})",
                                 file, dhat, 100.0 * static_cast<double>(c.in_range) / static_cast<double>(c.vertices),
                                 surface.name, c.in_range, c.vertices, c.pairs, c.min_distance, 0.5 * c.min_distance, edge));
}

bool is_shape_collider(const ColliderSpec& c) { return c.type != ColliderSpec::Type::mesh && c.type != ColliderSpec::Type::plane; }

std::string shape_collider_crossing(const ContactSpec& spec, const ContactSurface& surface, const Eigen::VectorXd& x0,
                                    const Eigen::VectorXd& x1, double t0, double t1, int max_samples) {
  if (!spec.enabled) return {};
  const Eigen::Index n = surface.points.size(), nf = surface.triangles.cols();
  Eigen::Matrix3Xd p0(3, n), p1(3, n);
  for (Eigen::Index i = 0; i < n; ++i) p0.col(i) = surface.points.point(x0, i), p1.col(i) = surface.points.point(x1, i);
  // The body's box over the frame (both ends: it moves linearly between them).
  const Vec3 lo = p0.rowwise().minCoeff().cwiseMin(p1.rowwise().minCoeff()), hi = p0.rowwise().maxCoeff().cwiseMax(p1.rowwise().maxCoeff());
  for (const ColliderSpec& c : spec.colliders) {
    if (!is_shape_collider(c)) continue;
    const ColliderShape shape = collider_shape(c);
    const ColliderPose pose = collider_pose(c);
    const ShapeBounds bounds = shape_bounds(shape);
    // Where the shape's bounding sphere is at time t (world), and how far it is from the body's box.
    const auto reach = [&](double t) {
      const ColliderFrame f = collider_frame(pose, t);
      const Vec3 centre = bounds.centre_at(f);
      return (centre.cwiseMax(lo).cwiseMin(hi) - centre).norm() - f.scale * bounds.radius;
    };
    // The path's length over the frame (16 chords: a frame may hold a key), and samples along it no farther
    // apart than a quarter of the shape's smallest size, tested only where the shape is near the body: the
    // frame is cut in at most 10 000 pieces, and a piece whose start and end are farther from the body's box
    // than the piece's length is skipped whole.
    const auto frame_at = [&](double s) { return collider_frame(pose, t0 + s * (t1 - t0)); };
    double travel = 0.0, smallest_scale = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 16; ++k) {
      const ColliderFrame a = frame_at(k / 16.0), b = frame_at((k + 1) / 16.0);
      travel += (b.translation - a.translation).norm() + std::max(a.scale, b.scale) * bounds.radius * (b.rotation - a.rotation).norm() +
                std::abs(b.scale - a.scale) * (bounds.centre.norm() + bounds.radius);
      smallest_scale = std::min({smallest_scale, a.scale, b.scale});
    }
    const double step = 0.25 * smallest_scale * bounds.smallest;
    const double samples = t1 > t0 ? std::max(1.0, std::ceil(travel / step)) : 0.0;
    const double pieces = std::min(std::max(samples, 1.0), 1e4), per_piece = samples / pieces;
    int near = 0;
    for (double piece = 0.0; piece < pieces; piece += 1.0) {
      if (samples > 0.0 && reach(t0 + piece / pieces * (t1 - t0)) > travel / pieces &&
          reach(t0 + (piece + 1.0) / pieces * (t1 - t0)) > travel / pieces)
        continue;  // nowhere near the body in this piece
      for (double k = std::ceil(piece * per_piece); k <= (piece + 1.0) * per_piece; k += 1.0) {
        const double s = samples > 0.0 ? k / samples : 1.0, t = t0 + s * (t1 - t0);
        if (reach(t) > 0.0) continue;
        if (++near > max_samples)
          return fmt::format("colliders[{}] ({}) moves {:.3g} between t = {:g} and {:g}, near the body, in more than {} steps of a "
                             "quarter of its size, too far to check that it does not pass through the surface: give it more "
                             "frames (or substeps) for that motion",
                             c.index, type_name(c.type), travel, t0, t1, max_samples);
        const ColliderFrame f = collider_frame(pose, t);
        const Vec3 centre = bounds.centre_at(f);
        const double r = f.scale * bounds.radius;
        for (Eigen::Index tri = 0; tri < nf; ++tri) {
          std::array<Vec3, 3> v;
          for (int j = 0; j < 3; ++j) {
            const Eigen::Index id = surface.triangles(j, tri);
            v[j] = (1.0 - s) * p0.col(id) + s * p1.col(id);
          }
          const Vec3 tlo = v[0].cwiseMin(v[1]).cwiseMin(v[2]), thi = v[0].cwiseMax(v[1]).cwiseMax(v[2]);
          if ((centre.cwiseMax(tlo).cwiseMin(thi) - centre).norm() > r) continue;
          if (shape_meets_triangle(shape, f.to_base(v[0]), f.to_base(v[1]), f.to_base(v[2])))
            return fmt::format("colliders[{}] ({}) meets {} at t = {:g}, triangle {}, between its points (the barrier keeps a "
                               "shape off the surface's points, not its faces: make the surface finer than the shape, or the "
                               "shape larger)",
                               c.index, type_name(c.type), surface.name, t, tri);
        }
      }
    }
  }
  return {};
}

void check_contact_start(const ContactSpec& spec, const ContactSurface& surface, const Eigen::Matrix3Xd& rest,
                         const Eigen::VectorXd& x0, double dhat, const std::string& file) {
  if (!spec.enabled) return;
  // Each colliding point strictly outside: `what` names the collider, `remedy` what to move.
  const auto far_enough = [&](const ShapeColliderTerm& term, int index, std::string_view what, const char* side, const char* remedy) {
    for (Eigen::Index i = 0; i < term.point_count(); ++i)
      if (const double d = term.point_distance(x0, i); !(d > 0.0))
        throw SceneError(fmt::format("{}: colliders[{}]: vertex {} of {} is {:g} from the {}, {} at the start (contact needs a "
                                     "separated start: {})",
                                     file, index, surface.colliding[static_cast<std::size_t>(i)], surface.name, d, what, side, remedy));
  };
  const EmbeddedPoints colliding = surface.points.select(surface.colliding);
  for (const PlaneColliderSpec& plane : spec.planes)
    far_enough(ShapeColliderTerm(colliding, plane_shape(plane), ColliderPose{}, dhat, 1.0), plane.index, "plane", "on or behind it",
               surface.skin ? "move the plane" : "move the plane or the mesh");
  for (const ColliderSpec& c : spec.colliders) {
    if (c.type != ColliderSpec::Type::mesh) {
      far_enough(ShapeColliderTerm(colliding, collider_shape(c), collider_pose(c), dhat, 1.0), c.index, type_name(c.type),
                 "on or inside it", surface.skin ? "move the collider" : "move the collider or the mesh");
    } else if (!std::isfinite(collider_term(c, surface, rest, dhat, 1.0)->energy(x0))) {
      throw SceneError(fmt::format("{}: colliders[{}]: {} touches the collider's ({}) at the start (distance 0): contact needs a "
                                   "separated start",
                                   file, c.index, surface.name, c.file.string()));
    }
  }
  // Faces too: no shape meets a triangle at the start, and none lies wholly inside the body.
  if (const std::string crossing = shape_collider_crossing(spec, surface, x0, x0, 0.0, 0.0); !crossing.empty())
    throw SceneError(fmt::format("{}: {} at the start (contact needs a separated start)", file, crossing));
  Eigen::Matrix3Xd points(3, surface.points.size());
  for (Eigen::Index i = 0; i < points.cols(); ++i) points.col(i) = surface.points.point(x0, i);
  for (const ColliderSpec& c : spec.colliders) {
    if (!is_shape_collider(c)) continue;
    const ColliderShape shape = collider_shape(c);
    const ColliderFrame f = collider_frame(collider_pose(c), 0.0);
    const Vec3 centre = shape_bounds(shape).centre_at(f);
    if (const double w = winding_number(points, surface.triangles, centre); std::abs(w) > 0.5)
      throw SceneError(fmt::format("{}: colliders[{}]: the {} lies inside {} at the start (winding number {:.2f} at its centre): "
                                   "contact needs a separated start; move the collider out of the body",
                                   file, c.index, type_name(c.type), surface.name, w));
  }
  if (!spec.self) return;
  const ContactTerm self(surface.triangles, surface.points, rest, dhat, 1.0);
  check_self_crowding(self, surface, x0, file);
  if (!std::isfinite(self.energy(x0)))
    throw SceneError(fmt::format("{}: contact.self: {} touches itself at the start (two of its triangles at distance 0): contact "
                                 "needs a separated start",
                                 file, surface.name));
}

}  // namespace snh
