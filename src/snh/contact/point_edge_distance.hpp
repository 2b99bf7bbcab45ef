#pragma once
// The squared distance from point p to segment (e0, e1), over the 9 coordinates (p, e0, e1):
//   p_e0: |p − e0|²,  p_e1: |p − e1|²,  p_e: |(p − e0) × (e1 − e0)|² / |e1 − e0|² (the line through e0, e1).
// Without a type, the type of point_edge_distance_type (the true distance to the segment).
#include "snh/contact/distance_core.hpp"
#include "snh/contact/distance_type.hpp"

namespace snh::contact {

[[nodiscard]] double point_edge_distance(const Vec3& p, const Vec3& e0, const Vec3& e1, PointEdgeType type);
[[nodiscard]] double point_edge_distance(const Vec3& p, const Vec3& e0, const Vec3& e1);
[[nodiscard]] Derivatives<9> point_edge_distance_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1,
                                                             PointEdgeType type);
[[nodiscard]] Derivatives<9> point_edge_distance_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1);

}  // namespace snh::contact
