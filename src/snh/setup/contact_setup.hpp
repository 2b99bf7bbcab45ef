#pragma once
// Contact as a scene sets it up: the surface it acts on, its resolved parameters, the terms (self-contact and
// its friction, planes, shapes and meshes with theirs) and the check that the start is separated. One piece of
// code serves a volume mesh's own boundary (its vertices as plain points) and a flesh's render surface
// embedded in the volume (points with weights) alike: the terms take their points either way
// (fem/embedded_points.hpp).
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/fem/embedded_points.hpp"
#include "snh/fem/term.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/setup/flesh.hpp"
#include "snh/setup/scene.hpp"

namespace snh {

/// The surface contact acts on: triangles over points of the volume.
struct ContactSurface {
  Eigen::Matrix3Xi triangles;  ///< over the points
  EmbeddedPoints points;       ///< every point (a volume's: each vertex as itself)
  std::vector<int> colliding;  ///< the points the triangles use, ascending: planes, shapes and meshes act on these
  std::string name;            ///< for messages: "the mesh's surface", "the render surface (welded)"
  bool skin = false;           ///< a flesh's render surface
};
/// A volume mesh's boundary (its vertices as themselves).
[[nodiscard]] ContactSurface boundary_contact_surface(const VolumeMesh& mesh);
/// A flesh's render surface (welded), its points embedded in the flesh's volume (contact_surface(flesh)).
[[nodiscard]] ContactSurface skin_contact_surface(const Flesh& flesh);

/// A scene's contact parameters, resolved: d̂ and κ (given, or the defaults of its kind of run), friction.
struct ContactParameters {
  double dhat = 0.0;
  double stiffness = 0.0;
  double friction = 0.0;       ///< μ (0: none)
  double slip_velocity = 0.0;  ///< friction's ε_v
};

/// The pose in time of a collider (empty: fixed), turning and scaling about its centroid.
[[nodiscard]] ColliderPose collider_pose(const ColliderSpec& c);
/// The shape of a plane, sphere, capsule or box collider (base frame).
[[nodiscard]] ColliderShape collider_shape(const ColliderSpec& c);
/// A fixed plane as a shape.
[[nodiscard]] ColliderShape plane_shape(const PlaneColliderSpec& p);
/// One collider's barrier on the surface (rest: the volume's rest positions).
[[nodiscard]] std::shared_ptr<ContactTermBase> collider_term(const ColliderSpec& c, const ContactSurface& surface,
                                                             const Eigen::Matrix3Xd& rest, double dhat, double stiffness);

/// The scene's contact terms on the surface, in the order their sums are taken: self-contact (and its
/// friction), each fixed plane (and its friction), `between` (a flesh's bones against its skin), each other
/// collider (and friction against shapes; meshes are frictionless).
[[nodiscard]] std::vector<std::shared_ptr<Term>> contact_terms(const ContactSpec& spec, const ContactSurface& surface,
                                                               const Eigen::Matrix3Xd& rest, const ContactParameters& p,
                                                               std::vector<std::shared_ptr<Term>> between = {});

/// Contact needs a separated start: every colliding point strictly above each plane and outside each shape,
/// none touching a mesh collider, and (self-contact) no two of the surface's primitives touching (a barrier
/// is +∞ there, and Newton could only report a state that is not finite). Throws SceneError naming `file`,
/// the collider and the point.
void check_contact_start(const ContactSpec& spec, const ContactSurface& surface, const Eigen::Matrix3Xd& rest,
                         const Eigen::VectorXd& x0, double dhat, const std::string& file);

/// Self-contact needs a d̂ below the surface's own spacing: at a d̂ near its edge length every vertex lies
/// within d̂ of triangles two rings away, and the barrier pushes the surface apart from itself everywhere
/// (and at a d̂ as large as the body, every primitive pairs with every other: memory and time grow as the
/// square of the surface). Throws SceneError naming `file`, d̂ and what to give instead when, at x0, more than
/// kCrowdedShare of the surface's vertices are in an active pair, or the broad phase finds more than
/// kCrowdedCandidates pairs a primitive (it stops there, so the check's memory stays bounded).
inline constexpr double kCrowdedShare = 0.25;
inline constexpr std::size_t kCrowdedCandidates = 64;
void check_self_crowding(const ContactTerm& self, const ContactSurface& surface, const Eigen::VectorXd& x0, const std::string& file);

/// A sphere, capsule or box: a collider whose barrier acts on the surface's points only.
[[nodiscard]] bool is_shape_collider(const ColliderSpec& c);

/// The barriers of shape colliders (sphere, capsule, box) keep the surface's points out of them, not its
/// edges and faces: a shape smaller than the triangles can slip between points. This checks the faces: over
/// a frame from t0 (the surface at x0) to t1 (at x1, the surface moving linearly between), the shape at
/// sample times no farther apart than a quarter of its smallest size (radius, half extent), each tested
/// exactly against every triangle near it. Returns one line naming the collider, the time and the triangle
/// where a shape meets the surface, or why the frame cannot be checked (more than `max_samples` samples
/// near the body); empty when every shape stays clear.
[[nodiscard]] std::string shape_collider_crossing(const ContactSpec& spec, const ContactSurface& surface, const Eigen::VectorXd& x0,
                                                  const Eigen::VectorXd& x1, double t0, double t1, int max_samples = 4096);

}  // namespace snh
