#pragma once
// Kinematic colliders as energy terms (IPC, Li et al. 2020): obstacles whose place is a function of time
// (a scene's "colliders" with their scripted "motion"), which the simulated surface stays clear of.
//
// ShapeColliderTerm: a convex shape, the points within a radius r of a core: a point (sphere), a segment
// (capsule), an axis-aligned box (box, r = 0), or a half-space (plane). Each simulated surface vertex at
// distance d outside the shape (d = |x − c(x)| − r, c the closest point of the core; for the plane the
// signed distance) adds κ b(d², d̂²) (contact/barrier.hpp); d ≤ 0 (on or inside the shape) makes the energy
// +∞. Derivatives, with n = (x − c)/|x − c| and J the Jacobian of the closest point c(x):
//     ∇d = n,   ∇²d = (I − n nᵀ)(I − J)/|x − c|
// (J = 0 at a point core, a segment's end or a box corner; a aᵀ, a the axis, inside a segment; the
// projector on the box's unclamped axes); ∇²d is symmetric, PSD, and n is in its null space, so the
// vertex's Hessian κ[(4d²b'' + 2b') n nᵀ + 2d b' ∇²d] has eigenvector n with κ(4d²b'' + 2b') and the rest
// ≤ 0 (b' ≤ 0): its PSD projection is κ max(4d²b'' + 2b', 0) n nᵀ (exact, no eigen-solve).
// max_step: d along a linear path x + τ dx is convex (the distance to a convex set is convex), so its
// tangent at τ lies below it: stepping to the tangent's root of d(τ) = d(0)/10 never passes the true
// root; repeated (Newton from the left on a convex function) it climbs to it. Each vertex keeps at least
// a tenth of its distance; a vertex not approaching (d′ ≥ 0) does not limit the step. A plane's d is linear
// along the step, so its root is exact at once: τ = 0.9 d / (−d′). The plane is the one barrier against a
// half-space, fixed (the ground: an empty pose) or moving.
//
// MeshColliderTerm: a triangle mesh against the simulated surface: simulated vertex – collider triangle,
// collider vertex – simulated triangle and simulated edge – collider edge candidates (the broad phase over
// the simulated surface and the part of the collider near it, pairs within one body left out; what is near
// is found by a box tree over the collider's triangles built once in its base frame, so the cost follows
// what is near, not the collider's size), each adding κ B with B its pair barrier
// (contact/pair_barrier.hpp: b of the classified point–triangle distance; m·b of the edge–edge distance,
// mollified where the edges are nearly parallel). The energy is IPC's sum over candidates (no merging:
// with the collider fixed the duplicates are few). Only the simulated vertices' blocks of each pair's
// gradient and Hessian are scattered (the collider's vertices are not DOFs); with projection, the pair's
// 12 by 12 Hessian is projected first, so its simulated blocks are PSD too. max_step: additive CCD
// (contact/ccd.hpp) of the swept candidates (boxes grown by d̂, as ContactTerm's), the collider fixed during
// the solve.
//
// Motion: each term holds a pose, a function of time mapping its base geometry (as given, at t = 0) to
// world space; at_time(t) moves it there. sweep(x, dx, t0, t1) says which fraction of the joint motion —
// the state from x to x + dx while the collider goes from its pose at t0 to its pose at t1 — keeps clear,
// each distance keeping a tenth of itself: the simulation splits a step whose sweep is not clear
// (simulation.cpp). The motion is taken as linear: for a mesh, every vertex of both bodies on the straight
// line between its two places (CCD); for a shape, each simulated vertex on the straight line between its
// two places in the shape's own frame (exact for a translation; for a rotation the chord of the arc). A
// shape's sweep that is not clear gives the part that keeps a fifth: the shortened part is checked again
// with its own poses, which lie off the first chord where the shape turns, and a part ending exactly at the
// tenth would be found a hair short again and again (a turning capsule then split one step hundreds of
// times, creeping towards the boundary).
//
// Statistics (contact_term_base.hpp): a shape's active pairs are its points within d̂, a mesh's its
// candidates within d̂.
//
// Embedded points (a flesh's render surface inside its lattice or tets): the terms take the colliding
// points as p_i = Σ_k W(k, i) x_{I(k, i)} (fem/embedded_points.hpp). Everything above then runs on
// the points: a shape's distance, barrier and derivatives per point, a mesh's candidates between the
// points' surface and the collider's; the derivatives over the points (a mesh pair's 12 by 12 Hessian
// projected first, then its simulated points' rows kept) are pulled back by the chain rule, g_x = Jᵀ g_p and
// H_x = Jᵀ H_p J, so the Hessian stays PSD; the stencil couples each point's cell (a shape: fixed, the
// cells' own coupling; a mesh: the cells of each pair's simulated points); max_step and sweep run on the
// points' motion W dx, exact as the map is linear. Plain points (a mesh's own boundary vertices, one weight 1
// each) keep their own arithmetic: direct gathers and scatters.
#include <array>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "snh/contact/box_tree.hpp"
#include "snh/fem/contact_term_base.hpp"
#include "snh/fem/embedded_points.hpp"
#include "snh/math/types.hpp"

namespace snh {

/// Where a collider is at time t: the map of its base geometry to world space. Shapes need a similarity
/// (rotation, translation, uniform scale); a mesh takes any affine map. Empty: fixed (the identity).
using ColliderPose = std::function<Eigen::Affine3d(double t)>;

/// A convex shape in its base frame: the points within `radius` of a core.
struct ColliderShape {
  enum class Kind { plane, sphere, capsule, box };
  Kind kind = Kind::sphere;
  /// plane: a point and the unit normal (the free side); sphere: the centre (a); capsule: the segment
  /// a–b; box: the centre (a) and the half extents (b, each > 0)
  Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
  double radius = 0.0;  ///< sphere, capsule (> 0); 0 for plane and box
};

/// A point's distance from outside a shape (negative or 0 on or inside it) and its derivatives.
struct ShapeDistance {
  double distance = 0.0;
  Vec3 normal = Vec3::Zero();   ///< ∇d
  Mat3 hessian = Mat3::Zero();  ///< ∇²d (where asked)
};
/// In the shape's frame. Throws nothing; a point on a segment or a box core gives the normal 0.
[[nodiscard]] ShapeDistance shape_distance(const ColliderShape& shape, const Vec3& q, bool hessian = false);

/// A shape's pose at one time as a similarity: world x = scale·R q + t.
struct ColliderFrame {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
  double scale = 1.0;
  [[nodiscard]] Vec3 to_base(const Vec3& x) const { return rotation.transpose() * (x - translation) / scale; }
};
/// The pose at t (the identity for an empty pose). Throws std::invalid_argument (one line) where it is not
/// a rotation, translation and uniform scale.
[[nodiscard]] ColliderFrame collider_frame(const ColliderPose& pose, double t);

/// The largest τ ∈ [0, 1] such that q + τ' dq stays at distance ≥ keep·d(q) from the shape for all τ' ≤ τ
/// (d convex along the line); 0 when q is not outside.
[[nodiscard]] double shape_step(const ColliderShape& shape, const Vec3& q, const Vec3& dq, double keep = 0.1);

class ShapeColliderTerm final : public ContactTermBase {
 public:
  /// points  the colliding points, each once: a mesh's boundary vertices as plain points
  ///         (EmbeddedPoints::plain), or a render surface's points embedded in the volume
  /// shape   a plane (fixed: an empty pose), sphere, capsule or box
  /// Throws std::invalid_argument (one line) for a shape that is not valid (radius, half extents, normal,
  /// non-finite numbers) or d̂ or κ not finite and > 0.
  ShapeColliderTerm(EmbeddedPoints points, ColliderShape shape, ColliderPose pose, double dhat, double stiffness);

  [[nodiscard]] std::string_view name() const override { return "collider"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;
  void at_time(double t) override;
  [[nodiscard]] bool moving() const override { return static_cast<bool>(pose_); }
  [[nodiscard]] double sweep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double t0, double t1) const override;

  /// The number of colliding points.
  [[nodiscard]] Eigen::Index point_count() const { return points_.size(); }
  /// The distance of point i from the shape at its current pose (negative inside; a plane's: signed).
  [[nodiscard]] double point_distance(const Eigen::VectorXd& x, Eigen::Index i) const;
  /// The points closer than d̂ at x.
  [[nodiscard]] int active_pairs(const Eigen::VectorXd& x) const override;
  /// The smallest distance over the points at the current pose (+∞ without points).
  [[nodiscard]] double min_distance(const Eigen::VectorXd& x) const override;

 private:
  using Frame = ColliderFrame;
  [[nodiscard]] Frame frame_at(double t) const { return collider_frame(pose_, t); }
  EmbeddedPoints points_;
  bool embedded_ = false;  ///< points with weights (not plain: scattered through them)
  ColliderShape shape_;
  ColliderPose pose_;
  Frame frame_;
  double dhat_, kappa_;
};

class MeshColliderTerm final : public ContactTermBase {
 public:
  /// F            3 by #F triangles of the simulated surface over the points (ids into `points`)
  /// points       the simulated surface's vertices as points of the volume: a mesh's boundary as plain
  ///              vertices (EmbeddedPoints::every(#V)), or a render surface embedded in the volume
  /// volume_rest  3 by #V the volume at rest (the points' rest positions give the mollifier thresholds)
  /// V, T         the collider's base vertices and triangles (T's ids into V)
  /// Throws std::invalid_argument (one line) for ids out of range, a repeated vertex in a triangle,
  /// non-finite positions, d̂ or κ not finite and > 0.
  MeshColliderTerm(const Eigen::Matrix3Xi& F, EmbeddedPoints points, const Eigen::Matrix3Xd& volume_rest, Eigen::Matrix3Xd V,
                   const Eigen::Matrix3Xi& T, ColliderPose pose, double dhat, double stiffness);

  [[nodiscard]] std::string_view name() const override { return "mesh collider"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  [[nodiscard]] bool stencil_varies() const override { return true; }
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;
  void at_time(double t) override;
  [[nodiscard]] bool moving() const override { return static_cast<bool>(pose_); }
  [[nodiscard]] double sweep(const Eigen::VectorXd& x, const Eigen::VectorXd& dx, double t0, double t1) const override;

  /// The collider's vertices at the current pose (3 by #V of the collider).
  [[nodiscard]] const Eigen::Matrix3Xd& collider_vertices() const { return placed_; }
  [[nodiscard]] const Eigen::Matrix3Xi& collider_triangles() const { return collider_T_; }
  /// The candidate pairs between the two surfaces closer than d̂ at x.
  [[nodiscard]] int active_pairs(const Eigen::VectorXd& x) const override;
  /// The smallest distance between the two surfaces over candidates within d̂ at x; d̂ if there is none.
  [[nodiscard]] double min_distance(const Eigen::VectorXd& x) const override;

 private:
  struct Candidate {
    bool edge_edge;
    std::array<int, 4> local;  ///< ids into Near's columns (the simulated surface's vertices first, then the collider's near ones)
    double mollifier_threshold;
  };
  /// The candidates between the two bodies over a step, on the vertices they use: the simulated surface's
  /// (all, in local order) and then the collider's near the body (ascending), at the step's start (V) and
  /// its motion (D: empty for a static test).
  struct Near {
    Eigen::Matrix3Xd V, D;
    std::vector<Candidate> pairs;
  };
  /// The simulated surface's points at x (3 by #points).
  [[nodiscard]] Eigen::Matrix3Xd surface_at(const Eigen::VectorXd& x) const;
  /// The candidates within dhat of the step from S (the simulated surface's points) and C (the collider's
  /// vertices) by DS and DC (null: still). `indexed`: C is the collider at the current pose, and its tree
  /// finds what is near (otherwise every triangle of the collider is tested).
  [[nodiscard]] Near near(const Eigen::Matrix3Xd& S, const Eigen::Matrix3Xd* DS, const Eigen::Matrix3Xd& C, const Eigen::Matrix3Xd* DC,
                          bool indexed, double dhat) const;
  /// The collider's triangles (ids into T) whose box may come near [lo, hi] (world) at the current pose: from
  /// the tree where the pose can be inverted, else all of them; a superset, ascending.
  [[nodiscard]] std::vector<int> triangles_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  /// Every collider triangle's id, ascending.
  [[nodiscard]] std::vector<int> all_triangles() const;
  /// A candidate's ids with the collider's replaced by −1 (EmbeddedPoints::scatter's slots).
  [[nodiscard]] std::array<int, 4> simulated_slots(const std::array<int, 4>& local) const;
  /// The smallest CCD fraction of the candidates for their step (their count added to *tested).
  [[nodiscard]] double ccd(const Near& n, long long* tested = nullptr) const;
  [[nodiscard]] Eigen::Matrix3Xd placed_at(double t) const;
  /// The squared distances of the candidates within d̂ at x (the statistics).
  [[nodiscard]] std::vector<double> close_distances(const Eigen::VectorXd& x) const;
  std::vector<int> surface_vertices_;  ///< the point id of each simulated surface vertex (local id order)
  EmbeddedPoints points_;              ///< the simulated surface's points in local order
  bool embedded_ = false;              ///< points with weights (not plain: scattered through them)
  Eigen::Index volume_vertices_ = 0;
  int triangles_simulated_ = 0;        ///< triangles below this index are the simulated surface's
  Eigen::Matrix3Xi F_;                 ///< the simulated surface's triangles (local ids)
  Eigen::Matrix2Xi E_;                 ///< its edges
  Eigen::Matrix3Xd rest_;              ///< its points at rest
  Eigen::Matrix3Xd base_, placed_;     ///< collider vertices: base and at the current pose
  Eigen::Matrix3Xi collider_T_;
  Eigen::Matrix2Xi collider_E_;        ///< the collider's edges (its vertex ids), sorted
  Eigen::Matrix3Xi triangle_edges_;    ///< the columns of collider_E_ of each triangle's three edges
  std::vector<int> loose_;             ///< the collider's vertices in no triangle (tested one by one)
  contact::BoxTree tree_;              ///< over the collider's triangles in its base frame
  Eigen::Affine3d pose_now_ = Eigen::Affine3d::Identity();  ///< the current pose (at_time)
  ColliderPose pose_;
  double dhat_, kappa_;
};

}  // namespace snh
