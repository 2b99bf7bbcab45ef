#pragma once
// Which pair of features (vertex, edge interior, face interior) realises the distance between a point and
// a segment, a point and a triangle, or two segments. Each type names one smooth piece (distance_core.hpp),
// so the full distance is the piece of its type: continuous, C¹ across type boundaries (the pieces agree
// there in value and gradient), and C² inside each type (IPC, Li et al. 2020, §4 and its supplement).
#include <string_view>

#include "snh/math/types.hpp"

namespace snh::contact {

/// Point p against segment (e0, e1).
enum class PointEdgeType {
  p_e0,  ///< closest to endpoint e0 (also a zero-length segment)
  p_e1,  ///< closest to endpoint e1
  p_e,   ///< closest to the segment's interior: the point–line distance
};

/// Point p against triangle (t0, t1, t2); its edges are e0 = (t0, t1), e1 = (t1, t2), e2 = (t2, t0).
enum class PointTriangleType { p_t0, p_t1, p_t2, p_e0, p_e1, p_e2, p_t };

/// Segment a = (ea0, ea1) against segment b = (eb0, eb1). "ea_eb0" is eb0 against the interior of a, and so
/// on; ea_eb is the line–line distance (both interiors), never used for parallel segments.
enum class EdgeEdgeType { ea0_eb0, ea0_eb1, ea1_eb0, ea1_eb1, ea_eb0, ea_eb1, ea0_eb, ea1_eb, ea_eb };

[[nodiscard]] std::string_view to_string(PointEdgeType t);
[[nodiscard]] std::string_view to_string(PointTriangleType t);
[[nodiscard]] std::string_view to_string(EdgeEdgeType t);

/// The parameter s = (p − e0)·(e1 − e0)/|e1 − e0|² of the projection decides: s ≤ 0 → e0, s ≥ 1 → e1.
[[nodiscard]] PointEdgeType point_edge_distance_type(const Vec3& p, const Vec3& e0, const Vec3& e1);

/// The Voronoi region of p: the signs of the projections of p on the edges and of the barycentric
/// sub-areas (the region tests of Ericson, Real-Time Collision Detection §5.1.5). A degenerate triangle
/// (|(t1−t0)×(t2−t0)|² ≤ 1e-20 |t1−t0|²|t2−t0|²) never gets p_t: the nearest of its three edges decides.
[[nodiscard]] PointTriangleType point_triangle_distance_type(const Vec3& p, const Vec3& t0, const Vec3& t1,
                                                            const Vec3& t2);

/// The minimiser (s, t) ∈ [0,1]² of |ea0 + s a − eb0 − t b|² (a = ea1 − ea0, b = eb1 − eb0) decides: s = 0,
/// interior or 1 and likewise t. Parallel or nearly parallel segments (|a×b|² < kParallelThreshold·|a|²|b|²,
/// or a zero-length one) take the nearest of the four endpoint-against-segment distances instead, whose
/// pieces stay well conditioned (the line–line piece divides by |a×b|²).
[[nodiscard]] EdgeEdgeType edge_edge_distance_type(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0,
                                                  const Vec3& eb1);

/// sin² of the angle below which two segments count as parallel for edge_edge_distance_type.
inline constexpr double kParallelThreshold = 1e-20;

}  // namespace snh::contact
