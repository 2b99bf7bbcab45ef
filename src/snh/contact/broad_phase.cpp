#include "snh/contact/broad_phase.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace snh::contact {
namespace {

struct Box {
  Eigen::Vector3d lo, hi;
  int kind = 0;  ///< 0 vertex, 1 edge, 2 triangle
  int id = 0;
  bool oversize = false;  ///< over more than kMaxCells cells: tested against every box
  Eigen::Matrix<long long, 3, 1> low_cell = Eigen::Matrix<long long, 3, 1>::Zero();  ///< the grid cell of lo
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

Eigen::Matrix2Xi surface_edges(const Eigen::Matrix3Xi& F, Eigen::Matrix3Xi* of_triangle) {
  // Each triangle side as one integer (lower id in the high half: the order of (lower, higher)) with its
  // place (3 t + k), sorted: a run of equal keys is one edge.
  std::vector<std::pair<std::uint64_t, int>> sides;
  sides.reserve(static_cast<std::size_t>(3 * F.cols()));
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint32_t>(F(k, f)), b = static_cast<std::uint32_t>(F((k + 1) % 3, f));
      sides.push_back({static_cast<std::uint64_t>(std::min(a, b)) << 32 | std::max(a, b), static_cast<int>(3 * f + k)});
    }
  std::sort(sides.begin(), sides.end());
  std::vector<std::uint64_t> keys;
  if (of_triangle) of_triangle->resize(3, F.cols());
  for (const auto& [key, place] : sides) {
    if (keys.empty() || keys.back() != key) keys.push_back(key);
    if (of_triangle) (*of_triangle)(place % 3, place / 3) = static_cast<int>(keys.size() - 1);
  }
  Eigen::Matrix2Xi E(2, static_cast<Eigen::Index>(keys.size()));
  for (std::size_t e = 0; e < keys.size(); ++e)
    E.col(static_cast<Eigen::Index>(e)) << static_cast<int>(keys[e] >> 32), static_cast<int>(keys[e] & 0xffffffffU);
  return E;
}

Candidates broad_phase(const Eigen::Matrix3Xd& V0, const Eigen::Matrix3Xd& V1, const Eigen::Matrix3Xi& F,
                       const Eigen::Matrix2Xi& E, double dhat, std::size_t max_candidates) {
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

  // A uniform grid of cells about the size of the boxes: each box is listed in the cells it covers, and
  // only boxes sharing a cell are tested. A pair is reported from one cell only, the one holding the low
  // corner of the two boxes' overlap, so it is met once. Boxes covering more than kMaxCells cells (a long
  // swept step) are tested against every box instead.
  Candidates out;
  if (boxes.empty()) return out;
  Eigen::Vector3d lo = boxes.front().lo, hi = boxes.front().hi;
  double extent = 0.0;
  for (const Box& b : boxes) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
    extent += (b.hi - b.lo).maxCoeff();
  }
  // Each entry packs a cell's key (13 bits per axis) and a box's index (25 bits) into one integer to sort.
  constexpr int kBits = 13, kIndexBits = 25;
  constexpr long long kMaxCells = 64;
  double h = 2.0 * extent / static_cast<double>(boxes.size());  // twice the mean: fewer cells to sort (docs/results.md)
  h = std::max({h, (hi - lo).maxCoeff() / static_cast<double>(1 << kBits), std::numeric_limits<double>::min()});
  const auto cell = [&](const Eigen::Vector3d& p) {
    return ((p - lo) / h).array().floor().cast<long long>().min((1LL << kBits) - 1).max(0LL).matrix().eval();
  };
  const auto key = [](const Eigen::Matrix<long long, 3, 1>& c) {
    return static_cast<std::uint64_t>(c[0] | (c[1] << kBits) | (c[2] << (2 * kBits)));
  };
  constexpr std::uint64_t mask = (std::uint64_t{1} << kIndexBits) - 1;
  // The candidates among boxes that overlap: a vertex and a triangle not its own, two edges sharing no vertex.
  const auto vertex_triangle = [&](const Box& v, const Box& t) {
    if (!(F.col(t.id).array() == v.id).any()) out.vertex_triangle.push_back({v.id, t.id});
  };
  const auto edge_edge = [&](const Box& a, const Box& b) {
    const Eigen::Vector2i ea = E.col(a.id), eb = E.col(b.id);
    if (ea[0] != eb[0] && ea[0] != eb[1] && ea[1] != eb[0] && ea[1] != eb[1])
      out.edge_edge.push_back({std::min(a.id, b.id), std::max(a.id, b.id)});
  };
  if (boxes.size() >= (std::size_t{1} << kIndexBits))
    throw std::invalid_argument("broad_phase: " + std::to_string(boxes.size()) + " primitives, more than the 2^25 it can index");
  std::vector<std::uint64_t> entries;  // key << kIndexBits | box, sorted: boxes of a cell together, by kind
  std::vector<int> oversize;
  entries.reserve(8 * boxes.size());
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const Eigen::Matrix<long long, 3, 1> a = cell(boxes[i].lo), b = cell(boxes[i].hi);
    boxes[i].low_cell = a;
    if ((b - a + Eigen::Matrix<long long, 3, 1>::Ones()).prod() > kMaxCells) {
      oversize.push_back(static_cast<int>(i));
      boxes[i].oversize = true;
      continue;
    }
    for (long long z = a[2]; z <= b[2]; ++z)
      for (long long y = a[1]; y <= b[1]; ++y)
        for (long long x = a[0]; x <= b[0]; ++x)
          entries.push_back(static_cast<std::uint64_t>(key({x, y, z})) << kIndexBits | static_cast<std::uint64_t>(i));
  }
  std::sort(entries.begin(), entries.end());
  // Within a cell its boxes come in box order: vertices, edges, triangles (as `boxes` holds them). A pair is
  // reported where the cell is the componentwise largest of the two boxes' lowest cells (floor is monotone,
  // so that is the cell of the low corner of their overlap).
  const auto begin_of = [&](int kind, std::size_t from, std::size_t to) {
    while (from < to && boxes[entries[from] & mask].kind < kind) ++from;
    return from;
  };
  const auto over_limit = [&] { return out.vertex_triangle.size() + out.edge_edge.size() > max_candidates; };
  for (std::size_t g = 0; g < entries.size();) {
    if (over_limit()) break;
    std::size_t end = g;
    const std::uint64_t here = entries[g] >> kIndexBits;
    while (end < entries.size() && entries[end] >> kIndexBits == here) ++end;
    const std::size_t edges = begin_of(1, g, end), triangles = begin_of(2, edges, end);
    const auto reported_here = [&](const Box& a, const Box& b) { return key(a.low_cell.cwiseMax(b.low_cell)) == here; };
    for (std::size_t i = g; i < edges && !over_limit(); ++i) {
      const Box& v = boxes[entries[i] & mask];
      for (std::size_t j = triangles; j < end; ++j) {
        const Box& t = boxes[entries[j] & mask];
        if (overlap(v, t) && reported_here(v, t)) vertex_triangle(v, t);
      }
    }
    for (std::size_t i = edges; i < triangles && !over_limit(); ++i) {
      const Box& a = boxes[entries[i] & mask];
      for (std::size_t j = i + 1; j < triangles; ++j) {
        const Box& b = boxes[entries[j] & mask];
        if (overlap(a, b) && reported_here(a, b)) edge_edge(a, b);
      }
    }
    g = end;
  }
  for (const int i : oversize) {
    if (over_limit()) break;
    const Box& a = boxes[static_cast<std::size_t>(i)];
    for (std::size_t j = 0; j < boxes.size(); ++j) {
      const Box& b = boxes[j];
      if ((b.oversize && j < static_cast<std::size_t>(i)) || !overlap(a, b)) continue;  // two oversize boxes: met once
      if (a.kind == 1 && b.kind == 1 && a.id != b.id) edge_edge(a, b);
      else if (a.kind == 0 && b.kind == 2) vertex_triangle(a, b);
      else if (a.kind == 2 && b.kind == 0) vertex_triangle(b, a);
    }
  }
  // Each pair is met once (the grid reports it from one cell; of two oversize boxes, the first reports it), so
  // the count is exact: past the limit (checked per box) the lists hold only some, at most a box's pairs more.
  if (over_limit()) {
    out.complete = false;
    return out;
  }
  std::sort(out.vertex_triangle.begin(), out.vertex_triangle.end());
  std::sort(out.edge_edge.begin(), out.edge_edge.end());
  return out;
}

}  // namespace snh::contact
