#include "snh/contact/broad_phase.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace snh::contact {
namespace {

struct Box {
  Eigen::Vector3d lo, hi;
  int kind = 0;  ///< 0 vertex, 1 edge, 2 triangle
  int id = 0;
};

bool overlap(const Box& a, const Box& b) {
  return (a.lo.array() <= b.hi.array()).all() && (b.lo.array() <= a.hi.array()).all();
}

template <int K>
Box box_of(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& V1, const Eigen::Matrix<int, K, 1>& ids, double grow,
           int kind, int id) {
  Box b{V0.col(ids[0]), V0.col(ids[0]), kind, id};
  for (int k = 0; k < K; ++k) {
    b.lo = b.lo.cwiseMin(V0.col(ids[k])).cwiseMin(V1.col(ids[k]));
    b.hi = b.hi.cwiseMax(V0.col(ids[k])).cwiseMax(V1.col(ids[k]));
  }
  b.lo.array() -= grow;
  b.hi.array() += grow;
  return b;
}

template <class Matrix>
void check_ids(const Matrix& ids, Eigen::Index n, const char* name) {
  for (Eigen::Index c = 0; c < ids.cols(); ++c)
    for (Eigen::Index r = 0; r < ids.rows(); ++r)
      if (ids(r, c) < 0 || ids(r, c) >= n)
        throw std::invalid_argument(std::string("broad_phase: ") + name + " column " + std::to_string(c) +
                                    " has vertex id " + std::to_string(ids(r, c)) + " outside [0, " +
                                    std::to_string(n) + ")");
}

}  // namespace

Eigen::Matrix2Xi surface_edges(const Eigen::Matrix3Xi& F) {
  std::vector<std::array<int, 2>> edges;
  edges.reserve(3 * F.cols());
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(k, f), b = F((k + 1) % 3, f);
      edges.push_back({std::min(a, b), std::max(a, b)});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Eigen::Matrix2Xi E(2, static_cast<Eigen::Index>(edges.size()));
  for (std::size_t e = 0; e < edges.size(); ++e) E.col(static_cast<Eigen::Index>(e)) << edges[e][0], edges[e][1];
  return E;
}

Candidates broad_phase(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& V1, const Eigen::Matrix3Xi& F,
                       const Eigen::Matrix2Xi& E, double dhat) {
  if (V0.cols() != V1.cols())
    throw std::invalid_argument("broad_phase: V0 has " + std::to_string(V0.cols()) + " vertices, V1 " +
                                std::to_string(V1.cols()));
  if (!V0.allFinite() || !V1.allFinite()) throw std::invalid_argument("broad_phase: non-finite vertex position");
  if (!(dhat >= 0.0) || !std::isfinite(dhat))
    throw std::invalid_argument("broad_phase: dhat = " + std::to_string(dhat) + " must be finite and >= 0");
  check_ids(F, V0.cols(), "triangle");
  check_ids(E, V0.cols(), "edge");

  std::vector<Box> boxes;
  boxes.reserve(static_cast<std::size_t>(V0.cols() + E.cols() + F.cols()));
  const double grow = 0.5 * dhat;
  for (Eigen::Index v = 0; v < V0.cols(); ++v)
    boxes.push_back(box_of<1>(V0, V1, Eigen::Matrix<int, 1, 1>(static_cast<int>(v)), grow, 0, static_cast<int>(v)));
  for (Eigen::Index e = 0; e < E.cols(); ++e)
    boxes.push_back(box_of<2>(V0, V1, E.col(e), grow, 1, static_cast<int>(e)));
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    boxes.push_back(box_of<3>(V0, V1, F.col(f), grow, 2, static_cast<int>(f)));

  // The sweep axis: the one along which the box centres spread most.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Box& b : boxes) {
    lo = lo.cwiseMin(b.lo + b.hi);
    hi = hi.cwiseMax(b.lo + b.hi);
  }
  int axis = 0;
  if (!boxes.empty()) (hi - lo).maxCoeff(&axis);
  std::sort(boxes.begin(), boxes.end(), [axis](const Box& a, const Box& b) {
    if (a.lo[axis] != b.lo[axis]) return a.lo[axis] < b.lo[axis];
    return a.kind != b.kind ? a.kind < b.kind : a.id < b.id;
  });

  // Open boxes per kind: those whose upper bound on the axis is not yet passed.
  std::array<std::vector<const Box*>, 3> open;
  Candidates out;
  for (const Box& b : boxes) {
    for (auto& list : open)
      list.erase(std::remove_if(list.begin(), list.end(), [&](const Box* o) { return o->hi[axis] < b.lo[axis]; }),
                 list.end());
    if (b.kind == 0) {
      for (const Box* t : open[2])
        if (overlap(b, *t) && !(F.col(t->id).array() == b.id).any()) out.vertex_triangle.push_back({b.id, t->id});
    } else if (b.kind == 2) {
      for (const Box* v : open[0])
        if (overlap(b, *v) && !(F.col(b.id).array() == v->id).any()) out.vertex_triangle.push_back({v->id, b.id});
    } else {
      const Eigen::Vector2i eb = E.col(b.id);
      for (const Box* o : open[1]) {
        const Eigen::Vector2i eo = E.col(o->id);
        if (overlap(b, *o) && eb[0] != eo[0] && eb[0] != eo[1] && eb[1] != eo[0] && eb[1] != eo[1])
          out.edge_edge.push_back({std::min(b.id, o->id), std::max(b.id, o->id)});
      }
    }
    open[b.kind].push_back(&b);
  }
  std::sort(out.vertex_triangle.begin(), out.vertex_triangle.end());
  std::sort(out.edge_edge.begin(), out.edge_edge.end());
  // Unique by construction (each pair is met once, when its later box opens); unique() keeps that honest.
  out.vertex_triangle.erase(std::unique(out.vertex_triangle.begin(), out.vertex_triangle.end()),
                            out.vertex_triangle.end());
  out.edge_edge.erase(std::unique(out.edge_edge.begin(), out.edge_edge.end()), out.edge_edge.end());
  return out;
}

}  // namespace snh::contact
