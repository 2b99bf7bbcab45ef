#include "snh/contact/point_triangle_distance.hpp"

namespace snh::contact {

// Points: 0 = p, 1 = t0, 2 = t1, 3 = t2; edge e_i runs from t_i to t_{i+1}.
double point_triangle_distance(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                               PointTriangleType type) {
  const Points<4> x = {p, t0, t1, t2};
  switch (type) {
    case PointTriangleType::p_t0: return point_point_value(x, 0, 1);
    case PointTriangleType::p_t1: return point_point_value(x, 0, 2);
    case PointTriangleType::p_t2: return point_point_value(x, 0, 3);
    case PointTriangleType::p_e0: return point_line_value(x, 0, 1, 2);
    case PointTriangleType::p_e1: return point_line_value(x, 0, 2, 3);
    case PointTriangleType::p_e2: return point_line_value(x, 0, 3, 1);
    case PointTriangleType::p_t: break;
  }
  return point_plane_value(x, 0, 1, 2, 3);
}

double point_triangle_distance(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  return point_triangle_distance(p, t0, t1, t2, point_triangle_distance_type(p, t0, t1, t2));
}

Derivatives<12> point_triangle_distance_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2,
                                                    PointTriangleType type) {
  const Points<4> x = {p, t0, t1, t2};
  switch (type) {
    case PointTriangleType::p_t0: return point_point_piece(x, 0, 1);
    case PointTriangleType::p_t1: return point_point_piece(x, 0, 2);
    case PointTriangleType::p_t2: return point_point_piece(x, 0, 3);
    case PointTriangleType::p_e0: return point_line_piece(x, 0, 1, 2);
    case PointTriangleType::p_e1: return point_line_piece(x, 0, 2, 3);
    case PointTriangleType::p_e2: return point_line_piece(x, 0, 3, 1);
    case PointTriangleType::p_t: break;
  }
  return point_plane_piece(x, 0, 1, 2, 3);
}

Derivatives<12> point_triangle_distance_derivatives(const Vec3& p, const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  return point_triangle_distance_derivatives(p, t0, t1, t2, point_triangle_distance_type(p, t0, t1, t2));
}

}  // namespace snh::contact
