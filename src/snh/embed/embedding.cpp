#include "snh/embed/embedding.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "snh/math/parallel.hpp"

namespace snh {
namespace {

/// How far, in cube edges, a point may lie outside a lattice cube and still count as in it.
constexpr double kCubeTolerance = 1e-6;
/// How far, in the tet mesh's bounding-box diagonals, a point may lie outside every tet and still be clamped.
constexpr double kTetTolerance = 1e-6;

void check_points(const Eigen::Matrix3Xd& points) {
  for (Eigen::Index p = 0; p < points.cols(); ++p)
    if (!points.col(p).allFinite())
      throw std::invalid_argument(
          fmt::format("point {} ({}, {}, {}) is not finite", p, points(0, p), points(1, p), points(2, p)));
}

/// Throws naming the first point flagged as failed, with `what` saying where it is not.
void throw_first_failure(const std::vector<unsigned char>& failed, const Eigen::Matrix3Xd& points, const char* what) {
  for (std::size_t p = 0; p < failed.size(); ++p)
    if (failed[p]) {
      const auto q = static_cast<Eigen::Index>(p);
      throw std::invalid_argument(
          fmt::format("point {} ({}, {}, {}) lies {}", p, points(0, q), points(1, q), points(2, q), what));
    }
}

/// The floor of x clamped to [0, n − 1] (x finite).
int clamped_floor(double x, int n) {
  return static_cast<int>(std::clamp(std::floor(std::clamp(x, -1.0, static_cast<double>(n))), 0.0, n - 1.0));
}

/// Barycentric coordinates of p in tet (x0, x1, x2, x3) by Cramer's rule, or none for a flat tet. A point
/// equal to a corner gets exactly that corner's unit coordinates.
std::optional<Eigen::Vector4d> barycentric(const std::array<Eigen::Vector3d, 4>& x, const Eigen::Vector3d& p) {
  const Eigen::Vector3d e1 = x[1] - x[0], e2 = x[2] - x[0], e3 = x[3] - x[0], d = p - x[0];
  const Eigen::Vector3d e23 = e2.cross(e3);
  const double det = e1.dot(e23);
  if (det == 0.0 || !std::isfinite(det)) return std::nullopt;
  for (int a = 0; a < 4; ++a)
    if (p == x[a]) return Eigen::Vector4d::Unit(a);
  Eigen::Vector4d l;
  l[1] = d.dot(e23) / det;
  l[2] = e1.dot(d.cross(e3)) / det;
  l[3] = e1.dot(e2.cross(d)) / det;
  l[0] = 1.0 - l[1] - l[2] - l[3];
  return l;
}

/// Tets binned by bounding box (grown by a tolerance) in a uniform grid over the mesh's bounding box: the
/// tets whose box meets cell g are bin[start[g] .. start[g+1]), in tet order.
struct TetGrid {
  Eigen::Vector3d lo, hi;  ///< the grid's box (the mesh's box grown by the tolerance)
  double size = 0.0;       ///< the cells' edge
  Eigen::Vector3i dims;
  std::vector<std::int64_t> start;
  std::vector<int> bin;

  [[nodiscard]] int cell_of(const Eigen::Vector3d& p, int a) const { return clamped_floor((p[a] - lo[a]) / size, dims[a]); }
  [[nodiscard]] std::size_t index(int i, int j, int k) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(dims.x()) *
                                             (static_cast<std::size_t>(j) + static_cast<std::size_t>(dims.y()) * k);
  }
};

TetGrid bin_tets(const VolumeMesh& tets, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double tol) {
  const Eigen::Index n = tets.cell_count();
  TetGrid g;
  g.lo = lo - Eigen::Vector3d::Constant(tol);
  g.hi = hi + Eigen::Vector3d::Constant(tol);
  const Eigen::Vector3d extent = g.hi - g.lo;
  // Cells about as large as a tet's box (its mean side, averaged over the tets), so each tet meets a few.
  double mean_side = 0.0;
  for (Eigen::Index c = 0; c < n; ++c) {
    Eigen::Vector3d a = tets.vertices.col(tets.cells(0, c)), b = a;
    for (int k = 1; k < 4; ++k) {
      a = a.cwiseMin(tets.vertices.col(tets.cells(k, c)));
      b = b.cwiseMax(tets.vertices.col(tets.cells(k, c)));
    }
    mean_side += (b - a).sum() / 3.0;
  }
  mean_side /= static_cast<double>(n);
  g.size = std::max(mean_side, extent.maxCoeff() * 1e-6);
  const double max_cells = 4.0 * static_cast<double>(n) + 64.0;
  for (;;) {
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
      const double d = std::max(1.0, std::ceil(extent[a] / g.size));
      g.dims[a] = static_cast<int>(std::min(d, 1e9));
      cells *= d;
    }
    if (cells <= max_cells) break;
    g.size *= 1.25;
  }
  // Counting sort of (cell, tet) pairs: count, prefix sums, fill in tet order.
  const auto range = [&](Eigen::Index c, std::array<int, 3>& first, std::array<int, 3>& last) {
    Eigen::Vector3d a = tets.vertices.col(tets.cells(0, c)), b = a;
    for (int k = 1; k < 4; ++k) {
      a = a.cwiseMin(tets.vertices.col(tets.cells(k, c)));
      b = b.cwiseMax(tets.vertices.col(tets.cells(k, c)));
    }
    a.array() -= tol;
    b.array() += tol;
    for (int d = 0; d < 3; ++d) {
      first[d] = g.cell_of(a, d);
      last[d] = g.cell_of(b, d);
    }
  };
  const std::size_t cells = static_cast<std::size_t>(g.dims.x()) * g.dims.y() * g.dims.z();
  g.start.assign(cells + 1, 0);
  std::array<int, 3> first{}, last{};
  for (Eigen::Index c = 0; c < n; ++c) {
    range(c, first, last);
    for (int k = first[2]; k <= last[2]; ++k)
      for (int j = first[1]; j <= last[1]; ++j)
        for (int i = first[0]; i <= last[0]; ++i) ++g.start[g.index(i, j, k) + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) g.start[c + 1] += g.start[c];
  g.bin.resize(static_cast<std::size_t>(g.start[cells]));
  std::vector<std::int64_t> fill(g.start.begin(), g.start.end() - 1);
  for (Eigen::Index c = 0; c < n; ++c) {
    range(c, first, last);
    for (int k = first[2]; k <= last[2]; ++k)
      for (int j = first[1]; j <= last[1]; ++j)
        for (int i = first[0]; i <= last[0]; ++i)
          g.bin[static_cast<std::size_t>(fill[g.index(i, j, k)]++)] = static_cast<int>(c);
  }
  return g;
}

Eigen::Matrix3Xd apply_to(const Embedding& e, const Eigen::Ref<const Eigen::Matrix3Xd>& X) {
  const Eigen::Index n = e.vertex.cols(), k = e.vertex.rows();
  if (e.weight.rows() != k || e.weight.cols() != n || static_cast<Eigen::Index>(e.cell.size()) != n)
    throw std::invalid_argument(fmt::format("embedding: {} cells, {} by {} vertices and {} by {} weights disagree",
                                            e.cell.size(), k, n, e.weight.rows(), e.weight.cols()));
  if (n > 0 && (e.vertex.minCoeff() < 0 || e.vertex.maxCoeff() >= X.cols()))
    for (Eigen::Index p = 0; p < n; ++p)
      for (Eigen::Index a = 0; a < k; ++a)
        if (e.vertex(a, p) < 0 || e.vertex(a, p) >= X.cols())
          throw std::invalid_argument(
              fmt::format("embedded point {} refers to vertex {} (the positions have {})", p, e.vertex(a, p), X.cols()));
  Eigen::Matrix3Xd out(3, n);
  ParallelErrors errors;
#pragma omp parallel for schedule(static) if (n >= 4096)
  for (Eigen::Index p = 0; p < n; ++p) {
    errors.run(p, [&] {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      for (Eigen::Index a = 0; a < k; ++a) x += e.weight(a, p) * X.col(e.vertex(a, p));
      out.col(p) = x;
    });
  }
  errors.rethrow();
  return out;
}

}  // namespace

Eigen::Matrix3Xd Embedding::apply(const Eigen::Matrix3Xd& X) const { return apply_to(*this, X); }

Eigen::Matrix3Xd Embedding::apply(const Eigen::VectorXd& x) const {
  if (x.size() % 3 != 0)
    throw std::invalid_argument(fmt::format("embedding: a flat position vector of size {}, not a multiple of 3", x.size()));
  return apply_to(*this, Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3));
}

namespace {

/// The cell of a split cube (cells first .. last − 1) that point p goes with: the piece of the nearest inside
/// sample that `sees` accepts (the segment from p to it), else of the nearest inside sample.
template <class Sees>
int choose_piece(const Lattice& L, int cube, int first, const Eigen::Vector3d& p, Sees&& sees) {
  const int s = L.samples, n = s * s * s, slot = L.touched_slot(cube);
  if (slot < 0 || s == 0) return first;
  const Eigen::Vector3i ijk = L.cube_ijk(cube);
  std::vector<std::pair<double, int>> order;  // (distance², sample)
  for (int i = 0; i < n; ++i)
    if (L.sample_piece[static_cast<std::size_t>(slot) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)] >= 0) {
      const Eigen::Vector3d abc(i % s + 0.5, (i / s) % s + 0.5, i / (s * s) + 0.5);
      order.emplace_back((L.origin + L.spacing * (ijk.cast<double>() + abc / s) - p).squaredNorm(), i);
    }
  if (order.empty()) return first;
  std::sort(order.begin(), order.end());
  int chosen = order.front().second;
  for (const auto& [d2, i] : order) {
    const Eigen::Vector3d abc(i % s + 0.5, (i / s) % s + 0.5, i / (s * s) + 0.5);
    if (sees(slot, L.origin + L.spacing * (ijk.cast<double>() + abc / s))) {
      chosen = i;
      break;
    }
  }
  return first + L.sample_piece[static_cast<std::size_t>(slot) * static_cast<std::size_t>(n) + static_cast<std::size_t>(chosen)];
}

template <class Sees>
Embedding embed_in_lattice_as(const Lattice& lattice, const Eigen::Matrix3Xd& points, Sees&& sees) {
  const Eigen::Vector3i& dims = lattice.dims;
  if (dims.minCoeff() < 1 || static_cast<double>(lattice.cell_at.size()) != static_cast<double>(dims.x()) * dims.y() * dims.z())
    throw std::invalid_argument(fmt::format("lattice of {} by {} by {} cubes has {} cube entries", dims.x(), dims.y(),
                                            dims.z(), lattice.cell_at.size()));
  if (!(lattice.spacing > 0.0) || !std::isfinite(lattice.spacing) || !lattice.origin.allFinite())
    throw std::invalid_argument(fmt::format("lattice spacing {} must be finite and > 0", lattice.spacing));
  if (lattice.mesh.type != CellType::hex8 || lattice.mesh.cells.rows() != 8)
    throw std::invalid_argument("lattice mesh must be of hex8 cells");
  check_points(points);

  const Eigen::Index n = points.cols();
  Embedding e;
  e.cell.assign(static_cast<std::size_t>(n), -1);
  e.vertex.resize(8, n);
  e.weight.resize(8, n);
  std::vector<unsigned char> failed(static_cast<std::size_t>(n), 0);
  ParallelErrors errors;
#pragma omp parallel for schedule(static) if (n >= 1024)
  for (Eigen::Index p = 0; p < n; ++p) {
    errors.run(p, [&] {
      const Eigen::Vector3d s = lattice.grid_coordinates(points.col(p));
      // The cube floor(s), then those whose faces (within the tolerance) the point is on; a point beyond the
      // grid by more than the tolerance is in none.
      std::array<std::array<int, 3>, 3> choices{};  // per axis: up to three cube indices, the first preferred
      std::array<int, 3> count{};
      bool outside = false;
      for (int a = 0; a < 3; ++a) {
        const int base = clamped_floor(s[a], dims[a]);
        const double u = s[a] - base;
        if (u < -kCubeTolerance || u > 1.0 + kCubeTolerance) outside = true;
        choices[a][count[a]++] = base;
        if (u <= kCubeTolerance && base > 0) choices[a][count[a]++] = base - 1;
        if (u >= 1.0 - kCubeTolerance && base < dims[a] - 1) choices[a][count[a]++] = base + 1;
      }
      int cell = -1;
      std::array<int, 3> cube{};
      for (int c = 0; c < count[2] && cell < 0 && !outside; ++c)
        for (int b = 0; b < count[1] && cell < 0; ++b)
          for (int a = 0; a < count[0] && cell < 0; ++a) {
            cube = {choices[0][a], choices[1][b], choices[2][c]};
            cell = lattice.cell_at[static_cast<std::size_t>(lattice.cube_index(cube[0], cube[1], cube[2]))];
          }
      if (cell >= 0 && cell < lattice.mesh.cell_count()) {
        const int c = lattice.cube_index(cube[0], cube[1], cube[2]);
        if (const auto [first, last] = lattice.cells_of_cube(c); last - first > 1)
          cell = choose_piece(lattice, c, first, points.col(p),
                              [&](int slot, const Eigen::Vector3d& target) { return sees(p, slot, target); });
      }
      if (cell < 0 || cell >= lattice.mesh.cell_count()) {
        failed[static_cast<std::size_t>(p)] = 1;
        e.cell[static_cast<std::size_t>(p)] = -1;
        e.vertex.col(p).setZero();
        e.weight.col(p).setZero();
        return;
      }
      // Trilinear weights of the corners c0..c7 (corner a at offset (a & 1, a >> 1 & 1, a >> 2 & 1)).
      const Eigen::Vector3d u = s - Eigen::Vector3d(cube[0], cube[1], cube[2]);
      e.cell[static_cast<std::size_t>(p)] = cell;
      for (int a = 0; a < 8; ++a) {
        const double wx = (a & 1) ? u.x() : 1.0 - u.x();
        const double wy = (a & 2) ? u.y() : 1.0 - u.y();
        const double wz = (a & 4) ? u.z() : 1.0 - u.z();
        e.vertex(a, p) = lattice.mesh.cells(a, cell);
        e.weight(a, p) = wx * wy * wz;
      }
    });
  }
  errors.rethrow();
  throw_first_failure(failed, points, "in no cell of the lattice");
  return e;
}

}  // namespace

Embedding embed_in_lattice(const Lattice& lattice, const Eigen::Matrix3Xd& points) {
  return embed_in_lattice_as(lattice, points, [](Eigen::Index, int, const Eigen::Vector3d&) { return false; });
}

Embedding embed_surface_in_lattice(const Lattice& lattice, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F,
                                   const Eigen::Matrix3Xd& points, const std::vector<int>& vertex) {
  if (static_cast<Eigen::Index>(vertex.size()) != points.cols())
    throw std::invalid_argument(fmt::format("embedding: {} points but {} surface vertex ids", points.cols(), vertex.size()));
  return embed_in_lattice_as(lattice, points, [&](Eigen::Index p, int slot, const Eigen::Vector3d& target) {
    const int own = vertex[static_cast<std::size_t>(p)];
    const Eigen::Vector3d from = points.col(p);
    for (std::int64_t k = lattice.triangle_start[static_cast<std::size_t>(slot)]; k < lattice.triangle_start[static_cast<std::size_t>(slot) + 1]; ++k) {
      const int f = lattice.triangle[static_cast<std::size_t>(k)];
      if (F(0, f) == own || F(1, f) == own || F(2, f) == own) continue;
      if (segment_meets_triangle(from, target, V.col(F(0, f)), V.col(F(1, f)), V.col(F(2, f)))) return false;
    }
    return true;
  });
}

Embedding embed_in_tets(const VolumeMesh& tets, const Eigen::Matrix3Xd& points) {
  if (tets.type != CellType::tet4 || tets.cells.rows() != 4)
    throw std::invalid_argument(fmt::format("embedding in tets needs a tet4 mesh, got {}", to_string(tets.type)));
  if (tets.cell_count() == 0) throw std::invalid_argument("embedding in a tet mesh with no tets");
  for (Eigen::Index c = 0; c < tets.cell_count(); ++c)
    for (int a = 0; a < 4; ++a)
      if (tets.cells(a, c) < 0 || tets.cells(a, c) >= tets.vertex_count())
        throw std::invalid_argument(
            fmt::format("tet {} refers to vertex {} (the mesh has {})", c, tets.cells(a, c), tets.vertex_count()));
  Eigen::Vector3d lo = tets.vertices.col(tets.cells(0, 0)), hi = lo;
  for (Eigen::Index c = 0; c < tets.cell_count(); ++c)
    for (int a = 0; a < 4; ++a) {
      const auto x = tets.vertices.col(tets.cells(a, c));
      if (!x.allFinite())
        throw std::invalid_argument(fmt::format("tet mesh vertex {} ({}, {}, {}) is not finite", tets.cells(a, c),
                                                x.x(), x.y(), x.z()));
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  check_points(points);

  const double tol = kTetTolerance * (hi - lo).norm();
  const TetGrid grid = bin_tets(tets, lo, hi, tol);
  const Eigen::Index n = points.cols();
  Embedding e;
  e.cell.assign(static_cast<std::size_t>(n), -1);
  e.vertex.resize(4, n);
  e.weight.resize(4, n);
  std::vector<unsigned char> failed(static_cast<std::size_t>(n), 0);
  ParallelErrors errors;
#pragma omp parallel for schedule(static) if (n >= 256)
  for (Eigen::Index p = 0; p < n; ++p) {
    errors.run(p, [&] {
      const Eigen::Vector3d x = points.col(p);
      int best = -1;
      double best_min = -std::numeric_limits<double>::infinity();
      Eigen::Vector4d best_weight = Eigen::Vector4d::Zero();
      if ((x.array() >= grid.lo.array()).all() && (x.array() <= grid.hi.array()).all()) {
        const std::size_t g = grid.index(grid.cell_of(x, 0), grid.cell_of(x, 1), grid.cell_of(x, 2));
        // The tet whose smallest coordinate is largest (the first such in tet order); a tet the point is
        // outside of counts only if the point is within tol of it, with its coordinates clamped.
        for (std::int64_t b = grid.start[g]; b < grid.start[g + 1]; ++b) {
          const int c = grid.bin[static_cast<std::size_t>(b)];
          const std::array<Eigen::Vector3d, 4> corner = {tets.vertices.col(tets.cells(0, c)), tets.vertices.col(tets.cells(1, c)),
                                                         tets.vertices.col(tets.cells(2, c)), tets.vertices.col(tets.cells(3, c))};
          const std::optional<Eigen::Vector4d> l = barycentric(corner, x);
          if (!l) continue;
          const double m = l->minCoeff();
          if (!(m > best_min)) continue;
          Eigen::Vector4d w = *l;
          if (m < 0.0) {
            w = w.cwiseMax(0.0);
            w /= w.sum();
            const Eigen::Vector3d q = w[0] * corner[0] + w[1] * corner[1] + w[2] * corner[2] + w[3] * corner[3];
            if (!((q - x).norm() <= tol)) continue;
          }
          best = c;
          best_min = m;
          best_weight = w;
        }
      }
      if (best < 0) {
        failed[static_cast<std::size_t>(p)] = 1;
        e.vertex.col(p).setZero();
        e.weight.col(p).setZero();
        return;
      }
      e.cell[static_cast<std::size_t>(p)] = best;
      for (int a = 0; a < 4; ++a) {  // element by element: GCC 12 warns (falsely) of a 512-bit load of the 4-vector
        e.vertex(a, p) = tets.cells(a, best);
        e.weight(a, p) = best_weight[a];
      }
    });
  }
  errors.rethrow();
  throw_first_failure(failed, points, "outside every tet of the mesh");
  return e;
}

}  // namespace snh
