#pragma once
// The squared distance from point p to triangle (t0, t1, t2), over the 12 coordinates (p, t0, t1, t2): the
// piece of the type (distance_type.hpp) — a vertex (|p − t_i|²), an edge's line (|(p − a) × (b − a)|² /
// |b − a|²) or the triangle's plane ((p − t0)·n)² / |n|² with n = (t1 − t0) × (t2 − t0).
// Without a type, the type of point_triangle_distance_type (the true distance to the triangle).
#include "snh/contact/distance_core.hpp"
#include "snh/contact/distance_type.hpp"

namespace snh::contact {

[[nodiscard]] double point_triangle_distance(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                             PointTriangleType type);
[[nodiscard]] double point_triangle_distance(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2);
[[nodiscard]] Derivatives<12> point_triangle_distance_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1,
                                                                  const Vec3& t2, PointTriangleType type);
[[nodiscard]] Derivatives<12> point_triangle_distance_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1,
                                                                  const Vec3& t2);

}  // namespace snh::contact
