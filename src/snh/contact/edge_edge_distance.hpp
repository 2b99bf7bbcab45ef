#pragma once
// The squared distance between segments a = (ea0, ea1) and b = (eb0, eb1), over the 12 coordinates
// (ea0, ea1, eb0, eb1): the piece of the type (distance_type.hpp) — two endpoints (|x − y|²), an endpoint
// and the other segment's line, or the two lines ((eb0 − ea0)·n)² / |n|² with n = (ea1 − ea0) × (eb1 − eb0).
// Without a type, the type of edge_edge_distance_type (the true distance between the segments).
// Near-parallel segments make the line–line piece ill-conditioned and the distance's Hessian jump where
// the type changes: IPC multiplies the edge–edge barrier by edge_edge_mollifier.hpp's factor there.
#include "snh/contact/distance_core.hpp"
#include "snh/contact/distance_type.hpp"

namespace snh::contact {

[[nodiscard]] double edge_edge_distance(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                        EdgeEdgeType type);
[[nodiscard]] double edge_edge_distance(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1);
[[nodiscard]] Derivatives<12> edge_edge_distance_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0,
                                                             const Vec3& eb1, EdgeEdgeType type);
[[nodiscard]] Derivatives<12> edge_edge_distance_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0,
                                                             const Vec3& eb1);

}  // namespace snh::contact
