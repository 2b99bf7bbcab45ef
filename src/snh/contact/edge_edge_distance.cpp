#include "snh/contact/edge_edge_distance.hpp"

namespace snh::contact {

// Points: 0 = ea0, 1 = ea1, 2 = eb0, 3 = eb1.
double edge_edge_distance(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1, EdgeEdgeType type) {
  const Points<4> x = {ea0, ea1, eb0, eb1};
  switch (type) {
    case EdgeEdgeType::ea0_eb0: return point_point_value(x, 0, 2);
    case EdgeEdgeType::ea0_eb1: return point_point_value(x, 0, 3);
    case EdgeEdgeType::ea1_eb0: return point_point_value(x, 1, 2);
    case EdgeEdgeType::ea1_eb1: return point_point_value(x, 1, 3);
    case EdgeEdgeType::ea_eb0: return point_line_value(x, 2, 0, 1);
    case EdgeEdgeType::ea_eb1: return point_line_value(x, 3, 0, 1);
    case EdgeEdgeType::ea0_eb: return point_line_value(x, 0, 2, 3);
    case EdgeEdgeType::ea1_eb: return point_line_value(x, 1, 2, 3);
    case EdgeEdgeType::ea_eb: break;
  }
  return line_line_value(x, 0, 1, 2, 3);
}

double edge_edge_distance(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1) {
  return edge_edge_distance(ea0, ea1, eb0, eb1, edge_edge_distance_type(ea0, ea1, eb0, eb1));
}

Derivatives<12> edge_edge_distance_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1,
                                               EdgeEdgeType type) {
  const Points<4> x = {ea0, ea1, eb0, eb1};
  switch (type) {
    case EdgeEdgeType::ea0_eb0: return point_point_piece(x, 0, 2);
    case EdgeEdgeType::ea0_eb1: return point_point_piece(x, 0, 3);
    case EdgeEdgeType::ea1_eb0: return point_point_piece(x, 1, 2);
    case EdgeEdgeType::ea1_eb1: return point_point_piece(x, 1, 3);
    case EdgeEdgeType::ea_eb0: return point_line_piece(x, 2, 0, 1);
    case EdgeEdgeType::ea_eb1: return point_line_piece(x, 3, 0, 1);
    case EdgeEdgeType::ea0_eb: return point_line_piece(x, 0, 2, 3);
    case EdgeEdgeType::ea1_eb: return point_line_piece(x, 1, 2, 3);
    case EdgeEdgeType::ea_eb: break;
  }
  return line_line_piece(x, 0, 1, 2, 3);
}

Derivatives<12> edge_edge_distance_derivatives(const Vec3& ea0, const Vec3& ea1, const Vec3& eb0, const Vec3& eb1) {
  return edge_edge_distance_derivatives(ea0, ea1, eb0, eb1, edge_edge_distance_type(ea0, ea1, eb0, eb1));
}

}  // namespace snh::contact
