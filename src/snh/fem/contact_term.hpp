#pragma once
// Contact as energy terms of the problem Newton minimises (IPC, Li et al. 2020): a barrier on the squared
// distances of the pairs of a triangle surface that come closer than d̂ (self-contact, ContactTerm), and a
// barrier keeping vertices above a plane (PlaneContactTerm). Both bound every Newton step by continuous
// collision detection (max_step), so no iterate the line search tries ever has a pair in contact.
//
// ContactTerm at x (the surface's vertices are vertices of the volume mesh: x holds them all):
//   1. candidates: the broad phase (contact/broad_phase.hpp) with the static boxes of x grown by d̂/2:
//      vertex–triangle and edge–edge pairs that share no vertex, over the surface's vertices only (the
//      volume's interior vertices never collide);
//   2. each candidate is reduced to the pair of closest features its distance type names (distance_type.hpp):
//        vertex–triangle (v, t)  → point–point (v, t_i), point–edge (v, edge of t) or point–triangle (v, t)
//        edge–edge (a, b)        → an edge–edge pair when the edges are nearly parallel (|a×b|² below the
//                                   mollifier threshold ε of their rest positions: the mollified energy
//                                   m·b, whatever the type) or when the type is the interior–interior one
//                                   ea_eb; otherwise the point–edge or point–point pair of its type;
//      and kept when its squared distance s is below ŝ = d̂²;
//   3. duplicates merge: pairs are keyed by their closest features (point–point by the two vertex ids in
//      increasing order, point–edge by the vertex and the edge's ids in increasing order, point–triangle by
//      the vertex and the triangle, edge–edge by the two edges), each key kept ONCE, with a weight w = the
//      number of candidates that reduced to it. A vertex over an edge shared by two triangles gives one
//      point–edge pair of weight 2; over a surface vertex of valence k, one point–point pair of weight k
//      (an edge–edge candidate whose type is an endpoint one adds to the same key). Each distance and
//      barrier is computed once per key, and the energy is
//          E(x) = κ Σ_keys w · B_key(x)       (B the pair's barrier, pair_barrier.hpp; m·b for edge–edge)
//      which equals the sum over all candidates of their own barriers (IPC's original energy, what the
//      IPC Toolkit's collision set computes with its per-pair multiplicities). The weights are kept, not
//      set to 1, because counting each key once makes E jump: a vertex above a shared edge whose
//      projection moves from the edge into one triangle goes from one key (point–edge, both candidates)
//      to two (point–triangle and point–edge) with equal distances at the switch, so E would double there
//      (tested: ContactTerm.EnergyIsContinuousAcrossAClosestFeatureChange). With the weights E is
//      continuous and C¹ (each candidate's distance is), and C² inside each type.
//   4. the pairs are sorted by key and summed in that order (deterministic); the gradient is scattered
//      by vertex id into the DOF vector and the Hessian (per pair, PSD-projected when projection is asked)
//      into the layout. No pair below ŝ: nothing is added at all (bit-identical to a problem without it).
// stencil: each active pair's vertices coupled with each other (stencil_varies: the layout grows when new
// pairs appear). max_step: the broad phase of the swept boxes (x to x + dx, d̂ = 0) and additive CCD
// (contact/ccd.hpp) of every vertex–triangle and edge–edge candidate: the smallest t, in (0, 1] for a
// separated x.
#include <array>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/term.hpp"

namespace snh {

/// One contact pair of ContactTerm (exposed for tests and statistics).
struct ContactPair {
  enum class Kind { point_point, point_edge, point_triangle, edge_edge };
  Kind kind = Kind::point_triangle;
  /// Vertex ids (volume mesh): point–point (v, w), point–edge (v, e0, e1), point–triangle (v, t0, t1, t2),
  /// edge–edge (a0, a1, b0, b1); unused entries −1.
  std::array<int, 4> vertices{-1, -1, -1, -1};
  int weight = 0;                  ///< candidates merged into this pair
  double squared_distance = 0.0;   ///< s at the x the pairs were found for
  double mollifier_threshold = 0;  ///< edge–edge: ε of the rest positions
  [[nodiscard]] int arity() const { return kind == Kind::point_point ? 2 : kind == Kind::point_edge ? 3 : 4; }
};

class ContactTerm final : public Term {
 public:
  /// F          3 by #F triangles of the contact surface, vertex ids of the volume mesh (e.g.
  ///            boundary_triangles(mesh))
  /// rest       3 by #V rest positions of every vertex (the mollifier thresholds come from them)
  /// dhat       the distance below which pairs repel (> 0)
  /// stiffness  κ (> 0)
  /// Throws std::invalid_argument (one line) for a vertex id out of range, a degenerate triangle (a
  /// repeated vertex), d̂ or κ not finite and > 0, or non-finite rest positions.
  ContactTerm(Eigen::Matrix3Xi F, Eigen::Matrix3Xd rest, double dhat, double stiffness);

  [[nodiscard]] std::string_view name() const override { return "contact"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  [[nodiscard]] bool stencil_varies() const override { return true; }
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;

  /// The active pairs at x (s < ŝ), merged and sorted as described above.
  [[nodiscard]] std::vector<ContactPair> pairs(const Eigen::VectorXd& x) const;
  /// The smallest distance (not squared) over all candidate pairs within d̂ at x; d̂ if there is none.
  [[nodiscard]] double min_distance(const Eigen::VectorXd& x) const;

  [[nodiscard]] const Eigen::Matrix3Xi& triangles() const { return F_; }
  [[nodiscard]] const Eigen::Matrix2Xi& edges() const { return E_; }
  [[nodiscard]] double dhat() const { return dhat_; }
  [[nodiscard]] double stiffness() const { return kappa_; }

 private:
  /// The surface's vertices at x (3 by #surface vertices, in surface_vertices_ order).
  Eigen::Matrix3Xd positions(const Eigen::VectorXd& x) const;
  Eigen::Matrix3Xi F_, local_F_;        ///< triangles in volume-mesh ids and in surface ids
  Eigen::Matrix2Xi E_, local_E_;        ///< edges likewise
  std::vector<int> surface_vertices_;   ///< volume-mesh id of each surface vertex, increasing
  Eigen::Matrix3Xd rest_;
  double dhat_, kappa_;
};

/// IPC's automatic barrier stiffness (Li et al. 2020, §4.3 and its code's initial choice) when nothing is in
/// contact at the start: the smallest κ for which the barrier's Hessian 4 d₀ b''(d₀, ŝ) at a squared
/// distance d₀ = (1e-8 · bbox_diagonal)² weighs 1e11 times an average vertex mass, in IPC's incremental
/// potential scaled by h² (½|x − x̃|²_M + h²Ψ + κ̃ B):
///     κ̃ = 1e11 · m̄ / (4 d₀ b''(d₀, ŝ)),
/// so in snh's unscaled potential (Ψ + M/(2h²)|x − x̃|² + κ B) κ = κ̃ / h². IPC raises κ during a run when
/// distances keep shrinking; snh keeps it fixed. Throws std::invalid_argument (one line) for an argument
/// that is not finite and > 0.
[[nodiscard]] double ipc_barrier_stiffness(double bbox_diagonal, double dhat, double average_mass, double dt);

/// A fixed plane n·x = n·p that vertices stay above (on the side n points to): for each vertex at signed
/// distance d = n·(x − p) (n of unit length) with d² < d̂², the energy κ b(d², d̂²); a vertex at or below the
/// plane makes the energy +∞. The Hessian per vertex is κ(4d²b'' + 2b') n nᵀ (rank one; its projection
/// clamps the coefficient at 0). max_step: each vertex moving towards the plane keeps at least a tenth of
/// its distance (exact: the motion is linear), min 1.
class PlaneContactTerm final : public Term {
 public:
  /// vertices   the vertex ids that collide with the plane (each once; e.g. the surface's vertices)
  /// point, normal  a point of the plane and its normal (any non-zero length: it is normalised)
  /// Throws std::invalid_argument (one line) for a zero or non-finite normal, a non-finite point, d̂ or κ
  /// not finite and > 0, or a negative vertex id.
  PlaneContactTerm(std::vector<int> vertices, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double dhat,
                   double stiffness);

  [[nodiscard]] std::string_view name() const override { return "plane"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;
  /// Signed distance of vertex v above the plane at x.
  [[nodiscard]] double distance(const Eigen::VectorXd& x, int v) const;

 private:
  std::vector<int> vertices_;
  Eigen::Vector3d point_, normal_;
  double dhat_, kappa_;
};

}  // namespace snh
