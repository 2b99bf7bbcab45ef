#include "snh/setup/contact_setup.hpp"

#include <algorithm>
#include <cmath>
#include <string_view>

#include <fmt/format.h>

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
  if (spec.self && !std::isfinite(ContactTerm(surface.triangles, surface.points, rest, dhat, 1.0).energy(x0)))
    throw SceneError(fmt::format("{}: contact.self: {} touches itself at the start (two of its triangles at distance 0): contact "
                                 "needs a separated start",
                                 file, surface.name));
}

}  // namespace snh
