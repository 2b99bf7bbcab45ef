#pragma once
// The broad phase: which vertex–triangle and edge–edge pairs of a triangle surface may come within d̂ of
// each other during a step, found by box overlap (IPC's candidate sets, before the exact distances).
// Each primitive's box bounds its vertices at the start and at the end of the step (the box of a linearly
// swept primitive: every point of x + t·dx, t ∈ [0, 1], lies in it), grown by d̂/2 on every side, so two
// primitives that come within d̂ at any time of the step have overlapping boxes. Pairs that share a vertex
// are never candidates (their distance is 0 by construction; IPC leaves them to the elasticity).
// The method is a uniform grid: cells as large as the boxes' mean largest extent, each box listed in the
// cells it covers (a box over more than 64 cells is tested against every box instead), boxes sharing a cell
// tested, each pair reported from the one cell holding the low corner of the two boxes' overlap; the result
// is sorted, so it does not depend on the order of the search (deterministic). (It replaced a sort and
// sweep along one axis, which tested each box against every box open across the surface's cross-section:
// on a closed surface that is most of its boxes.)
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include <Eigen/Dense>

namespace snh::contact {

/// Candidate pairs, each list sorted lexicographically and free of duplicates.
struct Candidates {
  std::vector<std::array<int, 2>> vertex_triangle;  ///< (vertex, triangle column of F)
  std::vector<std::array<int, 2>> edge_edge;        ///< (edge, edge) column indices of E, first < second
  /// False when the search stopped at its limit (broad_phase's max_candidates): the lists then hold some of
  /// the pairs only, more than the limit in all.
  bool complete = true;
};

/// The undirected edges of a triangle list: 2 by #E, each column (lower id, higher id), columns sorted.
/// With `of_triangle`: 3 by #F, the column of triangle t's edge (F(k, t), F(k + 1 mod 3, t)) at (k, t).
[[nodiscard]] Eigen::Matrix2Xi surface_edges(const Eigen::Matrix3Xi& F, Eigen::Matrix3Xi* of_triangle = nullptr);

/// Candidates of the step from V0 to V1 (3 by #V each; pass V0 twice for a static test).
///   F  3 by #F triangles, E  2 by #E edges (e.g. surface_edges(F)), vertex ids in [0, #V)
///   dhat  the distance below which pairs interact (≥ 0)
///   max_candidates  the search stops (complete false) once it has found more pairs than this: a caller that
///                   must not spend memory in proportion to the square of the surface's size bounds it
/// Throws std::invalid_argument (one line) for non-finite positions, V0 and V1 of different sizes, an
/// index out of range, or dhat negative or non-finite.
[[nodiscard]] Candidates broad_phase(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& V1, const Eigen::Matrix3Xi& F,
                                     const Eigen::Matrix2Xi& E, double dhat,
                                     std::size_t max_candidates = std::numeric_limits<std::size_t>::max());

}  // namespace snh::contact
