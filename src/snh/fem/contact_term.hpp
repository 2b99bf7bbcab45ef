#pragma once
// Self-contact as an energy term of the problem Newton minimises (IPC, Li et al. 2020): a barrier on the
// squared distances of the pairs of a triangle surface that come closer than d̂ (ContactTerm). It bounds
// every Newton step by continuous collision detection (max_step), so no iterate the line search tries ever
// has a pair in contact. Planes and other colliders: collider_term.hpp.
//
// ContactTerm at x (the surface's vertices are points of the volume mesh, x holds the volume's vertices):
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
// pairs appear); stencil_ahead, what a rebuilt layout covers: every candidate within 4 d̂, its four points
// coupled. max_step: the broad phase of the swept boxes (x to x + dx, each grown by d̂/2, so a pair left
// out stays farther than d̂ apart over the whole step, while with boxes not grown a pair ending in touching
// could be missed by the rounding of the boxes' bounds, the ball of tests/setup/test_contact_scenes.cpp) and
// additive CCD (contact/ccd.hpp) of every vertex–triangle and edge–edge candidate: the smallest t, in
// (0, 1] for a separated x.
//
// Embedded surfaces (a flesh's render surface inside its lattice or tets): the surface's vertices are points
// of the volume, p_i = Σ_k W(k, i) x_{I(k, i)} (k = 8 trilinear or 4 barycentric weights). Everything above then runs on the points p = W x: candidates, pairs (adjacency by the surface's
// own vertex ids), merging, barriers. The pair's derivatives over its points (its 2 to 4 points, 6 to 12
// coordinates) are PSD-projected first (when asked) and then pulled back to the volume by the chain rule:
// g_x = Jᵀ g_p and H_x = Jᵀ H_p J with J the pair's weights (so H_x stays PSD); the stencil couples every
// volume vertex of the pair's cells (up to 32); max_step runs CCD on the points' motion dp = W dx, which is
// exactly linear in the step. Plain points (one weight 1 each: a mesh's own boundary) take their own path,
// plain gathers and scatters of the vertices' coordinates.
#include <array>
#include <vector>

#include <Eigen/Core>

#include "snh/contact/broad_phase.hpp"
#include "snh/contact/distance_core.hpp"
#include "snh/fem/contact_term_base.hpp"
#include "snh/fem/embedded_points.hpp"

namespace snh {

/// One contact pair of ContactTerm (exposed for tests and statistics).
struct ContactPair {
  enum class Kind { point_point, point_edge, point_triangle, edge_edge };
  Kind kind = Kind::point_triangle;
  /// Vertex ids (volume mesh; an embedded surface's: its point ids): point–point (v, w), point–edge (v, e0, e1), point–triangle (v, t0, t1, t2),
  /// edge–edge (a0, a1, b0, b1); unused entries −1.
  std::array<int, 4> vertices{-1, -1, -1, -1};
  int weight = 0;                  ///< candidates merged into this pair
  double squared_distance = 0.0;   ///< s at the x the pairs were found for
  double mollifier_threshold = 0;  ///< edge–edge: ε of the rest positions
  [[nodiscard]] int arity() const { return kind == Kind::point_point ? 2 : kind == Kind::point_edge ? 3 : 4; }
};

/// How much of a surface lies within d̂ of other parts of itself (ContactTerm::crowding).
struct Crowding {
  bool complete = true;             ///< false: the broad phase passed its limit (then only `candidates` is set)
  std::size_t candidates = 0;       ///< broad-phase pairs (boxes grown by d̂/2)
  Eigen::Index in_range = 0;        ///< surface vertices in an active pair
  Eigen::Index vertices = 0;        ///< surface vertices in all
  std::size_t pairs = 0;            ///< active pairs (merged)
  double min_distance = 0.0;        ///< the smallest distance of an active pair; d̂ with none
  double mean_edge = 0.0;           ///< the surface's mean edge length (0 without edges)
};

class ContactTerm final : public ContactTermBase {
 public:
  /// F            3 by #F triangles over the points (ids into `points`)
  /// points       the surface's vertices as points of the volume: a mesh's own boundary as plain vertices
  ///              (EmbeddedPoints::every(#V) with F = boundary_triangles(mesh)), or a render surface embedded
  ///              in the volume (k weights per point)
  /// volume_rest  3 by #V rest positions of the volume (the points' rest positions give the mollifier
  ///              thresholds)
  /// dhat         the distance below which pairs repel (> 0)
  /// stiffness    κ (> 0)
  /// Throws std::invalid_argument (one line) for a point id out of range, a degenerate triangle (a repeated
  /// vertex), a volume vertex id out of range, d̂ or κ not finite and > 0, or non-finite rest positions.
  ContactTerm(Eigen::Matrix3Xi F, EmbeddedPoints points, const Eigen::Matrix3Xd& volume_rest, double dhat, double stiffness);

  [[nodiscard]] std::string_view name() const override { return "contact"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  [[nodiscard]] bool stencil_varies() const override { return true; }
  /// The pairs within layout_reach() at x, each candidate's 4 points coupled whatever its closest features.
  void stencil_ahead(const Eigen::VectorXd& x, Stencil& out) const override;
  /// The distance within which stencil_ahead() couples pairs: kLayoutReach d̂.
  [[nodiscard]] double layout_reach() const { return kLayoutReach * dhat_; }
  static constexpr double kLayoutReach = 4.0;
  [[nodiscard]] double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const override;

  /// The active pairs at x (s < ŝ), merged and sorted as described above, their ids the points'.
  [[nodiscard]] std::vector<ContactPair> pairs(const Eigen::VectorXd& x) const;
  [[nodiscard]] int active_pairs(const Eigen::VectorXd& x) const override;
  /// The smallest distance (not squared) over all candidate pairs within d̂ at x; d̂ if there is none.
  [[nodiscard]] double min_distance(const Eigen::VectorXd& x) const override;
  /// How crowded the surface is at x, found with at most max_candidates broad-phase pairs (memory bounded:
  /// a d̂ as large as the body would otherwise pair every primitive with every other).
  [[nodiscard]] Crowding crowding(const Eigen::VectorXd& x, std::size_t max_candidates) const;
  /// The surface's vertices, edges and triangles, counted together.
  [[nodiscard]] std::size_t primitive_count() const {
    return surface_vertices_.size() + static_cast<std::size_t>(local_E_.cols() + local_F_.cols());
  }
  /// The surface's vertex positions at x (3 by #surface vertices: the points that F uses, in increasing
  /// order).
  [[nodiscard]] Eigen::Matrix3Xd positions(const Eigen::VectorXd& x) const;

  [[nodiscard]] const Eigen::Matrix3Xi& triangles() const { return F_; }  ///< over the points
  [[nodiscard]] const Eigen::Matrix2Xi& edges() const { return E_; }
  [[nodiscard]] double dhat() const { return dhat_; }
  [[nodiscard]] double stiffness() const { return kappa_; }

 private:
  /// The surface positions (*P, when asked) and active pairs (local ids) at x, kept for the last finite x
  /// asked: Newton asks the stencil, the derivatives and the energy at the same x, and the broad phase
  /// then runs once (not thread-safe, as the counters: a problem evaluates its terms one after another).
  const std::vector<ContactPair>& pairs_at(const Eigen::VectorXd& x, const Eigen::Matrix3Xd** P = nullptr) const;
  /// Numbers the surface's vertices (ids of F, increasing) and lists its edges.
  void number_surface(Eigen::Index id_count);
  /// The volume vertex of local surface vertex i (plain points).
  [[nodiscard]] int vertex_of(Eigen::Index i) const { return points_.vertex()(0, i); }
  /// The active pairs at the surface positions P among the candidates c, in local ids.
  std::vector<ContactPair> local_pairs(const Eigen::Matrix3Xd& P, const contact::Candidates& c) const;
  /// Adds a pair's derivatives (over its local points `ids`) to the volume's gradient and Hessian.
  template <int N>
  void scatter(const contact::Derivatives<N>& d, const std::array<int, 4>& ids, Eigen::VectorXd* gradient,
               const HessianValues* hessian) const;
  Eigen::Matrix3Xi F_, local_F_;        ///< triangles in point ids and in surface ids
  Eigen::Matrix2Xi E_, local_E_;        ///< edges likewise
  std::vector<int> surface_vertices_;   ///< the point id of each surface vertex, increasing
  Eigen::Matrix3Xd surface_rest_;       ///< rest positions of the surface vertices
  Eigen::Index volume_vertices_ = 0;    ///< #V of the x the term is given
  bool embedded_ = false;               ///< points with weights (not plain: gathered and scattered through them)
  EmbeddedPoints points_;               ///< the surface's points, in local order
  double dhat_, kappa_;
  mutable Eigen::VectorXd cache_x_;     ///< pairs_at's last x (empty: none)
  mutable Eigen::Matrix3Xd cache_positions_;
  mutable std::vector<ContactPair> cache_pairs_;
  /// The broad phase's candidates at the surface positions `candidates_at_`, their boxes grown by d̂ (not
  /// d̂/2): while no surface point has moved by more than d̂/2 in any coordinate since, they hold every pair
  /// within d̂ (a box of now lies within its box of then grown by d̂/2), so the narrow phase finds the same
  /// pairs as a new broad phase would (the extra candidates are farther than d̂ and dropped): bit-identical.
  mutable Eigen::Matrix3Xd candidates_at_;
  mutable contact::Candidates candidates_;
  [[nodiscard]] const contact::Candidates& candidates_near(const Eigen::Matrix3Xd& V) const;
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

}  // namespace snh
