#include "snh/contact/point_edge_distance.hpp"

namespace snh::contact {

// Points: 0 = p, 1 = e0, 2 = e1.
double point_edge_distance(const Vec3& p, const Vec3& e0, const Vec3& e1, PointEdgeType type) {
  const Points<3> x = {p, e0, e1};
  switch (type) {
    case PointEdgeType::p_e0: return point_point_value(x, 0, 1);
    case PointEdgeType::p_e1: return point_point_value(x, 0, 2);
    case PointEdgeType::p_e: break;
  }
  return point_line_value(x, 0, 1, 2);
}

double point_edge_distance(const Vec3& p, const Vec3& e0, const Vec3& e1) {
  return point_edge_distance(p, e0, e1, point_edge_distance_type(p, e0, e1));
}

Derivatives<9> point_edge_distance_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1, PointEdgeType type) {
  const Points<3> x = {p, e0, e1};
  switch (type) {
    case PointEdgeType::p_e0: return point_point_piece(x, 0, 1);
    case PointEdgeType::p_e1: return point_point_piece(x, 0, 2);
    case PointEdgeType::p_e: break;
  }
  return point_line_piece(x, 0, 1, 2);
}

Derivatives<9> point_edge_distance_derivatives(const Vec3& p, const Vec3& e0, const Vec3& e1) {
  return point_edge_distance_derivatives(p, e0, e1, point_edge_distance_type(p, e0, e1));
}

}  // namespace snh::contact
