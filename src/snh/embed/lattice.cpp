#include "snh/embed/lattice.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <map>
#include <stdexcept>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "snh/embed/winding_number.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/math/parallel.hpp"
#include "snh/math/union_find.hpp"

namespace snh {
namespace {

constexpr double kPad = 0.05;                          ///< margin around the bounding box, in cubes, each side
constexpr std::int64_t kMaxCubes = std::int64_t{1} << 28;  ///< so (dims + 1)³ grid nodes still fit an int


/// The grid: `resolution` cubes along the longest side of the bounding box of the vertices the triangles use,
/// with kPad of a cube to spare at either end; the other sides get as many cubes as cover them with at least
/// that margin. The grid is centred on the box. Its cells are not chosen yet.
Lattice empty_grid(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution) {
  Eigen::Vector3d lo = V.col(F(0, 0)), hi = lo;
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int a = 0; a < 3; ++a) {
      lo = lo.cwiseMin(V.col(F(a, f)));
      hi = hi.cwiseMax(V.col(F(a, f)));
    }
  const Eigen::Vector3d extent = hi - lo;
  const double longest = extent.maxCoeff();
  if (!(longest > 0.0) || !std::isfinite(longest))
    throw std::invalid_argument(
        fmt::format("lattice of a surface with no extent (every vertex at ({}, {}, {}))", lo.x(), lo.y(), lo.z()));
  Lattice L;
  L.spacing = longest / (resolution - 2.0 * kPad);
  double cubes = 1.0;
  for (int a = 0; a < 3; ++a) {
    const double n = std::max(1.0, std::ceil(extent[a] / L.spacing + 2.0 * kPad - 1e-9));
    cubes *= n;
    if (!(cubes <= static_cast<double>(kMaxCubes)))
      throw std::invalid_argument(fmt::format(
          "lattice resolution {} needs more than 2^28 cubes for a surface of extent ({}, {}, {})", resolution,
          extent.x(), extent.y(), extent.z()));
    L.dims[a] = static_cast<int>(n);
    L.origin[a] = lo[a] - 0.5 * (n * L.spacing - extent[a]);
  }
  return L;
}

/// The (cube, triangle) pairs of every cube a triangle overlaps, by cube then triangle, in cube units
/// (L.grid_coordinates, as embed_in_lattice), each cube grown by δ: 1e-9 of its edge, more for grids so long
/// that rounding of the coordinates could exceed that.
std::vector<std::pair<int, int>> cube_triangle_pairs(const Lattice& L, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F) {
  const Eigen::Vector3i& dims = L.dims;
  const double delta = 1e-9 + 16.0 * std::numeric_limits<double>::epsilon() * dims.maxCoeff();
  Eigen::Matrix3Xd Q(3, V.cols());
  for (Eigen::Index v = 0; v < V.cols(); ++v) Q.col(v) = L.grid_coordinates(V.col(v));
  const auto cube_range = [&](double x, int a) {
    return std::clamp(static_cast<int>(std::floor(std::clamp(x, -1.0, dims[a] + 1.0))), 0, dims[a] - 1);
  };
  std::vector<std::vector<std::pair<int, int>>> found(static_cast<std::size_t>(F.cols()));
  ParallelErrors overlap_errors;
#pragma omp parallel for schedule(dynamic, 64) if (F.cols() >= 256)
  for (Eigen::Index f = 0; f < F.cols(); ++f) {
    overlap_errors.run(f, [&] {
      const std::array<Eigen::Vector3d, 3> q = {Q.col(F(0, f)), Q.col(F(1, f)), Q.col(F(2, f))};
      const Eigen::Vector3d qlo = q[0].cwiseMin(q[1]).cwiseMin(q[2]), qhi = q[0].cwiseMax(q[1]).cwiseMax(q[2]);
      std::array<int, 3> first{}, last{};
      for (int a = 0; a < 3; ++a) {
        first[a] = cube_range(qlo[a] - 2.0 * delta, a);
        last[a] = cube_range(qhi[a] + 2.0 * delta, a);
      }
      for (int k = first[2]; k <= last[2]; ++k)
        for (int j = first[1]; j <= last[1]; ++j)
          for (int i = first[0]; i <= last[0]; ++i) {
            const Eigen::Vector3d centre(i + 0.5, j + 0.5, k + 0.5);
            if (triangle_overlaps_cube({q[0] - centre, q[1] - centre, q[2] - centre}, 0.5 + delta))
              found[static_cast<std::size_t>(f)].emplace_back(L.cube_index(i, j, k), static_cast<int>(f));
          }
    });
  }
  overlap_errors.rethrow();
  std::size_t total = 0;
  for (const auto& v : found) total += v.size();
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(total);
  for (auto& v : found) {
    pairs.insert(pairs.end(), v.begin(), v.end());
    std::vector<std::pair<int, int>>().swap(v);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

/// The winding number of each untouched cube (inside: |w| > ½, either orientation): untouched cubes, grouped
/// by face neighbours into regions the surface does not cross; on a closed surface each region is inside or
/// outside as a whole (the winding number is constant off the surface), asked at its first cube; on an open
/// one (`open`: holes let a region reach from inside to outside, where the generalized winding number varies
/// smoothly) every cube is asked. Touched cubes come back 0.
std::vector<float> cube_windings(const Lattice& L, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F,
                                 const std::vector<unsigned char>& touched, bool open) {
  const Eigen::Vector3i& dims = L.dims;
  const std::size_t n_cubes = touched.size();
  std::vector<int> region(n_cubes, -1);
  std::vector<int> seed;  // each region's first cube in grid order
  std::vector<int> stack;
  for (std::size_t c0 = 0; c0 < n_cubes; ++c0) {
    if (touched[c0] || region[c0] >= 0) continue;
    const int r = static_cast<int>(seed.size());
    seed.push_back(static_cast<int>(c0));
    region[c0] = r;
    if (open) continue;  // a region per cube
    stack.assign(1, static_cast<int>(c0));
    while (!stack.empty()) {
      const int c = stack.back();
      stack.pop_back();
      const Eigen::Vector3i ijk = L.cube_ijk(c);
      const int i = ijk.x(), j = ijk.y(), k = ijk.z();
      const std::array<std::array<int, 3>, 6> next = {
          {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}}};
      for (const auto& n : next) {
        if (n[0] < 0 || n[1] < 0 || n[2] < 0 || n[0] >= dims.x() || n[1] >= dims.y() || n[2] >= dims.z()) continue;
        const int m = L.cube_index(n[0], n[1], n[2]);
        if (touched[static_cast<std::size_t>(m)] || region[static_cast<std::size_t>(m)] >= 0) continue;
        region[static_cast<std::size_t>(m)] = r;
        stack.push_back(m);
      }
    }
  }
  const int regions = static_cast<int>(seed.size());
  std::vector<float> inside(seed.size(), 0.0f);
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 1) if (regions > 1)
  for (int r = 0; r < regions; ++r) {
    errors.run(r, [&] {
      const int c = seed[static_cast<std::size_t>(r)];
      const Eigen::Vector3d centre = L.origin + L.spacing * (L.cube_ijk(c).cast<double>() + Eigen::Vector3d::Constant(0.5));
      inside[static_cast<std::size_t>(r)] = static_cast<float>(winding_number(V, F, centre));
    });
  }
  errors.rethrow();
  std::vector<float> out(n_cubes, 0.0f);
  for (std::size_t c = 0; c < n_cubes; ++c)
    if (!touched[c]) out[c] = inside[static_cast<std::size_t>(region[c])];
  return out;
}

/// What the pieces are made of: the surface in cube units, the kept and touched cubes, and the samples.
struct PieceContext {
  const Lattice& L;
  const Eigen::Matrix3Xd& Q;  ///< the vertices in cube units
  const Eigen::Matrix3Xi& F;
  const std::vector<unsigned char>& keep;
  const std::vector<float>& winding;  ///< per cube not touched: its winding number
  int s;  ///< samples per edge
  /// Sample (a, b, c) of cube (i, j, k) in cube units.
  [[nodiscard]] Eigen::Vector3d sample(const Eigen::Vector3i& cube, const Eigen::Vector3i& abc) const {
    return cube.cast<double>() + (abc.cast<double>() + Eigen::Vector3d::Constant(0.5)) / s;
  }
  [[nodiscard]] Eigen::Vector3i cube_of(int c) const {
    return L.cube_ijk(c);
  }
  [[nodiscard]] int sample_index(const Eigen::Vector3i& abc) const { return abc.x() + s * (abc.y() + s * abc.z()); }
  /// Whether the segment p → q (cube units) meets a triangle of touched slot t (t < 0: none).
  [[nodiscard]] bool blocked(int t, const Eigen::Vector3d& p, const Eigen::Vector3d& q) const {
    if (t < 0) return false;
    for (std::int64_t k = L.triangle_start[static_cast<std::size_t>(t)]; k < L.triangle_start[static_cast<std::size_t>(t) + 1]; ++k) {
      const int f = L.triangle[static_cast<std::size_t>(k)];
      if (segment_meets_triangle(p, q, Q.col(F(0, f)), Q.col(F(1, f)), Q.col(F(2, f)))) return true;
    }
    return false;
  }
  /// Whether the segment p → q (cube units) stays inside the solid, starting from winding number w at p: the
  /// winding number jumps by ±1 at each triangle of slots t and u (either may be −1; a triangle in both counts
  /// once) that the segment crosses, and must stay above ½ in magnitude. A segment through a triangle's edge
  /// or vertex, or ending on one, does not count as inside (the jump there is not well defined).
  [[nodiscard]] bool through_solid(int t, int u, const Eigen::Vector3d& p, const Eigen::Vector3d& q, double w) const {
    std::array<std::pair<double, int>, 64> small{};
    std::vector<std::pair<double, int>> crossings;
    int count = 0;
    const auto slot_has = [&](int slot, int f) {
      const auto first = L.triangle.begin() + L.triangle_start[static_cast<std::size_t>(slot)];
      const auto last = L.triangle.begin() + L.triangle_start[static_cast<std::size_t>(slot) + 1];
      return std::binary_search(first, last, f);
    };
    const Eigen::Vector3d d = q - p;
    for (const int slot : {t, u}) {
      if (slot < 0) continue;
      for (std::int64_t k = L.triangle_start[static_cast<std::size_t>(slot)]; k < L.triangle_start[static_cast<std::size_t>(slot) + 1]; ++k) {
        const int f = L.triangle[static_cast<std::size_t>(k)];
        if (slot == u && t >= 0 && slot_has(t, f)) continue;
        const Eigen::Vector3d a = Q.col(F(0, f)), b = Q.col(F(1, f)), c = Q.col(F(2, f));
        const Eigen::Vector3d n = (b - a).cross(c - a);
        const double dp = n.dot(p - a), dq = n.dot(q - a);
        if ((dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || (dp == 0.0 && dq == 0.0)) continue;
        const double e0 = d.dot((a - p).cross(b - p)), e1 = d.dot((b - p).cross(c - p)), e2 = d.dot((c - p).cross(a - p));
        const bool hit = (e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0) || (e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0);
        if (!hit) continue;
        if (dp == 0.0 || dq == 0.0 || e0 == 0.0 || e1 == 0.0 || e2 == 0.0) return false;  // on an edge, a vertex or an end
        const std::pair<double, int> x{dp / (dp - dq), d.dot(n) < 0.0 ? 1 : -1};
        if (count < 64) small[static_cast<std::size_t>(count)] = x;
        else crossings.push_back(x);
        ++count;
      }
    }
    if (count > 64) crossings.insert(crossings.end(), small.begin(), small.end());
    else crossings.assign(small.begin(), small.begin() + count);
    std::sort(crossings.begin(), crossings.end());
    for (const auto& [at, jump] : crossings) {
      w += jump;
      if (std::abs(w) <= 0.5) return false;
    }
    return true;
  }
};

/// The pieces of touched slot t. Its samples are first grouped into regions that no triangle separates; each
/// region's winding number is taken from an untouched neighbour cube it reaches unblocked (beyond the grid: 0),
/// else computed at its first sample. Inside samples (|w| > ½) then form a piece when a segment joins them
/// through the solid (through_solid: a surface inside the solid, as where two meshes overlap, does not
/// separate; the skin between two fingers does). Writes each sample's piece (−1 outside) and winding number,
/// and returns the number of pieces.
int find_pieces(const PieceContext& P, const Eigen::Matrix3Xd& V, int t, signed char* label, float* winding) {
  const Lattice& L = P.L;
  const int s = P.s, n = s * s * s;
  const int c = L.touched[static_cast<std::size_t>(t)];
  const Eigen::Vector3i cube = P.cube_of(c);
  const auto position = [&](int i) { return P.sample(cube, Eigen::Vector3i(i % s, (i / s) % s, i / (s * s))); };
  const auto axis_pairs = [&](auto&& visit) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3i abc(i % s, (i / s) % s, i / (s * s));
      for (int a = 0; a < 3; ++a)
        if (abc[a] + 1 < s) visit(i, P.sample_index(abc + Eigen::Vector3i::Unit(a)));
    }
  };
  UnionFind regions(static_cast<std::size_t>(n));
  axis_pairs([&](int i, int k) {
    if (!P.blocked(t, position(i), position(k))) regions.join(i, k);
  });
  std::vector<double> w(static_cast<std::size_t>(n), std::numeric_limits<double>::quiet_NaN());  // per root
  for (int i = 0; i < n; ++i) {
    const int r = regions.root(i);
    if (!std::isnan(w[static_cast<std::size_t>(r)])) continue;
    const Eigen::Vector3i abc(i % s, (i / s) % s, i / (s * s));
    for (int a = 0; a < 3 && std::isnan(w[static_cast<std::size_t>(r)]); ++a)
      for (const int step : {-1, 1}) {
        if ((step < 0 && abc[a] != 0) || (step > 0 && abc[a] != s - 1)) continue;
        const Eigen::Vector3i nb = cube + step * Eigen::Vector3i::Unit(a);
        double there = 0.0;  // beyond the grid: outside
        if (nb[a] >= 0 && nb[a] < L.dims[a]) {
          const int m = L.cube_index(nb.x(), nb.y(), nb.z());
          if (L.touched_slot(m) >= 0) continue;
          there = P.winding[static_cast<std::size_t>(m)];
        }
        if (P.blocked(t, position(i), position(i) + static_cast<double>(step) / s * Eigen::Vector3d::Unit(a))) continue;
        w[static_cast<std::size_t>(r)] = there;
        break;
      }
  }
  std::vector<int> inside_samples;
  for (int i = 0; i < n; ++i) {
    double& wr = w[static_cast<std::size_t>(regions.root(i))];
    if (std::isnan(wr)) wr = winding_number(V, P.F, L.origin + L.spacing * position(i));
    winding[i] = static_cast<float>(wr);
    if (std::abs(wr) > 0.5) inside_samples.push_back(i);
  }
  // Pieces: inside samples joined through the solid, along the axes, then any two groups a segment joins
  // (material thinner than a sample's spacing, or running diagonally, leaves its samples apart along the axes).
  UnionFind pieces(static_cast<std::size_t>(n));
  axis_pairs([&](int i, int k) {
    if (std::abs(winding[i]) <= 0.5f || std::abs(winding[k]) <= 0.5f) return;
    if (regions.root(i) == regions.root(k) || P.through_solid(t, -1, position(i), position(k), winding[i])) pieces.join(i, k);
  });
  for (std::size_t a = 0; a < inside_samples.size(); ++a)
    for (std::size_t b = a + 1; b < inside_samples.size(); ++b) {
      const int i = inside_samples[a], k = inside_samples[b];
      if (pieces.root(i) != pieces.root(k) && P.through_solid(t, -1, position(i), position(k), winding[i])) pieces.join(i, k);
    }
  std::vector<int> piece(static_cast<std::size_t>(n), -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    label[i] = -1;
    if (std::abs(winding[i]) <= 0.5f) continue;
    int& p = piece[static_cast<std::size_t>(pieces.root(i))];
    if (p < 0) p = count++;
    label[i] = static_cast<signed char>(std::min(p, 127));
  }
  return count;
}

/// The connections across the face between cube c and its neighbour c + e_axis (both kept): pairs (piece of
/// c, piece of the neighbour). `pieces` per cube: the number of inside pieces its samples found (an untouched
/// cube: 1). `separated` is set when two cubes of at most one piece each both reach the face and nothing
/// connects them there.
std::vector<std::pair<int, int>> face_links(const PieceContext& P, const std::vector<int>& pieces_of, int c, int axis,
                                            bool& separated) {
  const Lattice& L = P.L;
  const int s = P.s;
  const Eigen::Vector3i cube = P.cube_of(c), next = cube + Eigen::Vector3i::Unit(axis);
  const int d = L.cube_index(next.x(), next.y(), next.z());
  const int tc = L.touched_slot(c), td = L.touched_slot(d);
  const int n = s * s * s;
  const auto label = [&](int slot, const Eigen::Vector3i& abc) -> int {
    return slot < 0 ? 0 : L.sample_piece[static_cast<std::size_t>(slot) * static_cast<std::size_t>(n) + static_cast<std::size_t>(P.sample_index(abc))];
  };
  const int pc = pieces_of[static_cast<std::size_t>(c)], pd = pieces_of[static_cast<std::size_t>(d)];
  separated = false;
  if (tc < 0 && td < 0) return {{0, 0}};  // no triangle in either: one solid
  std::vector<std::pair<int, int>> links;
  // The inside samples of each cube (piece, position, winding number), and the pieces with a sample on the
  // face's layer.
  struct Inside {
    int piece;
    Eigen::Vector3d x;
    double w;
  };
  const auto winding_at = [&](int slot, int cube_index, int i) -> double {
    return slot < 0 ? P.winding[static_cast<std::size_t>(cube_index)]
                    : L.sample_winding[static_cast<std::size_t>(slot) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)];
  };
  std::vector<Inside> in_c, in_d;
  std::vector<int> facing_c, facing_d;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3i abc(i % s, (i / s) % s, i / (s * s));
    if (const int l = label(tc, abc); l >= 0) {
      in_c.push_back({l, P.sample(cube, abc), winding_at(tc, c, i)});
      if (abc[axis] == s - 1 && std::find(facing_c.begin(), facing_c.end(), l) == facing_c.end()) facing_c.push_back(l);
    }
    if (const int l = label(td, abc); l >= 0) {
      in_d.push_back({l, P.sample(next, abc), winding_at(td, d, i)});
      if (abc[axis] == 0 && std::find(facing_d.begin(), facing_d.end(), l) == facing_d.end()) facing_d.push_back(l);
    }
  }
  // Two pieces are connected across the face when a segment between an inside sample of each stays inside the
  // solid: the samples facing each other across the face are tried first, then every pair.
  const auto connected = [&](int la, int lb) {
    const double across = 1.0 / s + 1e-9;
    for (const bool near : {true, false})
      for (const Inside& a : in_c)
        if (a.piece == la)
          for (const Inside& b : in_d)
            if (b.piece == lb && ((a.x - b.x).norm() <= across) == near && P.through_solid(tc, td, a.x, b.x, a.w)) return true;
    return false;
  };
  for (int la = 0; la < pc; ++la)
    for (int lb = 0; lb < pd; ++lb)
      if (connected(la, lb)) links.emplace_back(la, lb);
  if (pc <= 1 && pd <= 1) {  // no split: shared unless both hold material and nothing connects it across
    separated = links.empty() && pc == 1 && pd == 1;
    if (separated) return {};
    return {{0, 0}};
  }
  // A sliver (a touched cube whose samples are all outside: one cell) joins the pieces that reach the face,
  // else the piece of the sample nearest to it, so that it never floats free.
  const auto sliver_links = [&](int slot_other, const std::vector<int>& facing, bool sliver_is_c) {
    std::vector<int> join = facing;
    if (join.empty()) {
      for (int layer = 0; layer < s && join.empty(); ++layer)
        for (int i = 0; i < n && join.empty(); ++i) {
          const Eigen::Vector3i abc(i % s, (i / s) % s, i / (s * s));
          if (abc[axis] != (sliver_is_c ? layer : s - 1 - layer)) continue;
          if (const int l = label(slot_other, abc); l >= 0) join.push_back(l);
        }
    }
    for (const int l : join) links.emplace_back(sliver_is_c ? 0 : l, sliver_is_c ? l : 0);
  };
  if (pc == 0) sliver_links(td, facing_d, true);
  if (pd == 0) sliver_links(tc, facing_c, false);
  return links;
}

/// The number of pieces of every cube: 0 for a cube not kept or a touched one whose samples are all outside, 1
/// for a kept cube no triangle meets; the touched cubes' samples labelled (L.sample_piece) on the way.
std::vector<int> count_pieces(Lattice& L, const PieceContext& P, const Eigen::Matrix3Xd& V) {
  const std::vector<unsigned char>& keep = P.keep;
  const int s = L.samples;
  std::vector<int> pieces_of(keep.size(), 0);
  for (std::size_t c = 0; c < keep.size(); ++c) pieces_of[c] = keep[c] ? 1 : 0;
  if (s == 0) return pieces_of;
  const int touched = static_cast<int>(L.touched.size());
  const auto per_cube = static_cast<std::size_t>(s * s * s);
  L.sample_piece.assign(static_cast<std::size_t>(touched) * per_cube, -1);
  L.sample_winding.assign(static_cast<std::size_t>(touched) * per_cube, 0.0f);
  std::vector<int> count(static_cast<std::size_t>(touched), 0);
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 16) if (touched >= 64)
  for (int t = 0; t < touched; ++t)
    errors.run(t, [&] {
      count[static_cast<std::size_t>(t)] = find_pieces(P, V, t, L.sample_piece.data() + static_cast<std::size_t>(t) * per_cube,
                                                       L.sample_winding.data() + static_cast<std::size_t>(t) * per_cube);
    });
  errors.rethrow();
  for (int t = 0; t < touched; ++t) pieces_of[static_cast<std::size_t>(L.touched[static_cast<std::size_t>(t)])] = count[static_cast<std::size_t>(t)];
  return pieces_of;
}

/// Cells in grid order: one per piece, at least one per kept cube.
void number_cells(Lattice& L, const std::vector<unsigned char>& keep, const std::vector<int>& pieces_of) {
  L.cell_at.assign(keep.size(), -1);
  L.cube_of_cell.clear();
  L.piece_of_cell.clear();
  L.split_cubes = 0;
  for (std::size_t c = 0; c < keep.size(); ++c) {
    if (!keep[c]) continue;
    L.cell_at[c] = static_cast<int>(L.cube_of_cell.size());
    const int copies = std::max(1, pieces_of[c]);
    if (copies > 1) ++L.split_cubes;
    for (int p = 0; p < copies; ++p) {
      L.cube_of_cell.push_back(static_cast<int>(c));
      L.piece_of_cell.push_back(p);
    }
  }
}

/// The connections across the +x, +y and +z faces of each kept cube (by its first cell), and the cubes near a
/// split or a separation (whose nodes are grouped: group_at_node()).
struct FaceLinks {
  std::vector<std::array<std::vector<std::pair<int, int>>, 3>> links;
  std::vector<unsigned char> near_split;
  std::vector<int> part;  ///< per cell: the part (cells joined through the faces' links) it belongs to
  [[nodiscard]] bool joined(const Lattice& L, int low_cube, int axis, int piece_low, int piece_high) const {
    const auto& face = links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(low_cube)])][static_cast<std::size_t>(axis)];
    return std::find(face.begin(), face.end(), std::pair{piece_low, piece_high}) != face.end();
  }
};

/// A sliver (a touched cube whose samples are all outside) joins the pieces whose material reaches its faces;
/// between two parts that the other links keep apart (a prop just beyond a limb's end) it would bridge them.
/// Each sliver keeps its links to the one part it touches most (then the first), and is marked near a split;
/// `part` then numbers the parts the links make (a node whose cells lie in more than one part is grouped:
/// group_at_node()).
template <class Above>
void keep_slivers_to_one_part(const Lattice& L, const std::vector<int>& pieces_of, const std::vector<int>& kept, const Above& above,
                              FaceLinks& out) {
  const auto cells = static_cast<int>(L.cube_of_cell.size());
  UnionFind parts(static_cast<std::size_t>(cells));
  const auto cell_of = [&](int cube, int piece) { return L.cell_at[static_cast<std::size_t>(cube)] + piece; };
  const auto sliver = [&](int cube) { return pieces_of[static_cast<std::size_t>(cube)] == 0; };
  // Parts through the links between cubes that are not slivers.
  for (const int c : kept)
    for (int a = 0; a < 3; ++a)
      if (const int d = above(c, a); d >= 0 && !sliver(c) && !sliver(d))
        for (const auto& [pc, pd] : out.links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(c)])][static_cast<std::size_t>(a)])
          parts.join(cell_of(c, pc), cell_of(d, pd));
  const Eigen::Vector3i& dims = L.dims;
  for (const int c : kept) {
    if (!sliver(c)) continue;
    // The sliver's links on its six faces: (the neighbour's cell, the face's list, the entry).
    struct Link {
      int cell;
      std::vector<std::pair<int, int>>* face;
      std::size_t entry;
    };
    std::vector<Link> found;
    const Eigen::Vector3i ijk = L.cube_ijk(c);
    for (int a = 0; a < 3; ++a) {
      const int step = a == 0 ? 1 : a == 1 ? dims.x() : dims.x() * dims.y();
      if (const int d = above(c, a); d >= 0 && !sliver(d)) {
        auto& face = out.links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(c)])][static_cast<std::size_t>(a)];
        for (std::size_t e = 0; e < face.size(); ++e) found.push_back({cell_of(d, face[e].second), &face, e});
      }
      if (ijk[a] > 0) {
        const int b = c - step;
        if (!L.cell_at.empty() && L.cell_at[static_cast<std::size_t>(b)] >= 0 && !sliver(b)) {
          auto& face = out.links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(b)])][static_cast<std::size_t>(a)];
          for (std::size_t e = 0; e < face.size(); ++e) found.push_back({cell_of(b, face[e].first), &face, e});
        }
      }
    }
    if (found.empty()) continue;
    std::map<int, int> count;  // part → links
    for (const Link& l : found) ++count[parts.root(l.cell)];
    if (count.size() < 2) {
      parts.join(cell_of(c, 0), found.front().cell);
      continue;
    }
    int best = count.begin()->first;
    for (const auto& [root, n] : count)
      if (n > count[best]) best = root;
    std::vector<std::pair<std::vector<std::pair<int, int>>*, std::size_t>> drop;
    for (const Link& l : found)
      if (parts.root(l.cell) != best) drop.emplace_back(l.face, l.entry);
    std::sort(drop.begin(), drop.end(), [](const auto& x, const auto& y) { return x.first != y.first ? x.first < y.first : x.second > y.second; });
    for (const auto& [face, entry] : drop) face->erase(face->begin() + static_cast<std::ptrdiff_t>(entry));
    out.near_split[static_cast<std::size_t>(c)] = 1;
    for (const Link& l : found) out.near_split[static_cast<std::size_t>(L.cube_of_cell[static_cast<std::size_t>(l.cell)])] = 1;
    parts.join(cell_of(c, 0), best);
  }
  // Slivers next to slivers: joined through their links too.
  for (const int c : kept)
    for (int a = 0; a < 3; ++a)
      if (const int d = above(c, a); d >= 0 && (sliver(c) || sliver(d)))
        for (const auto& [pc, pd] : out.links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(c)])][static_cast<std::size_t>(a)])
          parts.join(cell_of(c, pc), cell_of(d, pd));
  out.part.resize(static_cast<std::size_t>(cells));
  for (int i = 0; i < cells; ++i) out.part[static_cast<std::size_t>(i)] = parts.root(i);
}

FaceLinks link_faces(const Lattice& L, const PieceContext& P, const std::vector<int>& pieces_of) {
  const std::vector<unsigned char>& keep = P.keep;
  const Eigen::Vector3i& dims = L.dims;
  FaceLinks out;
  out.near_split.assign(keep.size(), 0);
  if (L.samples == 0) return out;
  out.links.resize(L.cube_of_cell.size());
  std::vector<int> kept;
  for (std::size_t c = 0; c < keep.size(); ++c)
    if (keep[c]) kept.push_back(static_cast<int>(c));
  const auto above = [&](int c, int a) {  // the kept cube after c along axis a, or −1
    if (P.cube_of(c)[a] + 1 >= dims[a]) return -1;
    const int d = c + (a == 0 ? 1 : a == 1 ? dims.x() : dims.x() * dims.y());
    return keep[static_cast<std::size_t>(d)] ? d : -1;
  };
  std::vector<unsigned char> separated(keep.size() * 3, 0);
  ParallelErrors errors;
#pragma omp parallel for schedule(dynamic, 64) if (kept.size() >= 256)
  for (std::size_t i = 0; i < kept.size(); ++i) {
    errors.run(static_cast<std::int64_t>(i), [&] {
      const int c = kept[i];
      for (int a = 0; a < 3; ++a) {
        if (above(c, a) < 0) continue;
        bool sep = false;
        out.links[static_cast<std::size_t>(L.cell_at[static_cast<std::size_t>(c)])][static_cast<std::size_t>(a)] =
            face_links(P, pieces_of, c, a, sep);
        separated[static_cast<std::size_t>(c) * 3 + static_cast<std::size_t>(a)] = sep ? 1 : 0;
      }
    });
  }
  errors.rethrow();
  for (const int c : kept) {
    if (pieces_of[static_cast<std::size_t>(c)] > 1) out.near_split[static_cast<std::size_t>(c)] = 1;
    for (int a = 0; a < 3; ++a) {
      const int d = above(c, a);
      if (d < 0) continue;
      if (separated[static_cast<std::size_t>(c) * 3 + static_cast<std::size_t>(a)] || pieces_of[static_cast<std::size_t>(c)] > 1 ||
          pieces_of[static_cast<std::size_t>(d)] > 1)
        out.near_split[static_cast<std::size_t>(c)] = out.near_split[static_cast<std::size_t>(d)] = 1;
    }
  }
  keep_slivers_to_one_part(L, pieces_of, kept, above, out);
  return out;
}

/// The cells at one grid node: each with the corner it meets the node by and its cube's offset bit there
/// (dx + 2 dy + 4 dz from the node's lower cube).
struct NodeCells {
  std::vector<int> cell, corner, bit;
  std::array<int, 8> cube_at{};  ///< by offset bit: the cube, or −1
  bool clean = true;             ///< no cube near a split: one vertex, as without pieces
};

/// The groups of the cells at a node that are connected through a face's links around it; each group's root.
/// Cells that meet there only along an edge or at a corner get a vertex each: of one part, they are joined
/// through faces elsewhere, and a vertex they shared would be a hinge, a joint with no material around it
/// whose nearly free rotation made Newton creep where such flesh was squeezed (docs/results.md, "Where the
/// 25k contact frames creep"); of two parts, the skin keeps them apart.
UnionFind group_at_node(const Lattice& L, const FaceLinks& F, const NodeCells& at) {
  const int n = static_cast<int>(at.cell.size());
  UnionFind groups(static_cast<std::size_t>(n));
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) {
      const int ba = at.bit[static_cast<std::size_t>(a)], bb = at.bit[static_cast<std::size_t>(b)];
      if (ba == bb) continue;  // two pieces of one cube
      const int differ = ba ^ bb;
      const int ca = at.cube_at[static_cast<std::size_t>(ba)], cb = at.cube_at[static_cast<std::size_t>(bb)];
      if (differ == 1 || differ == 2 || differ == 4) {
        const bool a_low = (ba & differ) == 0;
        const int pa = L.piece_of_cell[static_cast<std::size_t>(at.cell[static_cast<std::size_t>(a)])];
        const int pb = L.piece_of_cell[static_cast<std::size_t>(at.cell[static_cast<std::size_t>(b)])];
        if (F.joined(L, a_low ? ca : cb, differ == 1 ? 0 : differ == 2 ? 1 : 2, a_low ? pa : pb, a_low ? pb : pa)) groups.join(a, b);
      }
    }
  return groups;
}

/// Whether the kept cubes around a node (by offset bit; −1: none) are connected through the faces they share
/// around it (cubes whose bits differ in one place).
bool faces_join_around(const std::array<int, 8>& cube_at) {
  int present = 0;
  for (int b = 0; b < 8; ++b)
    if (cube_at[static_cast<std::size_t>(b)] >= 0) present |= 1 << b;
  int reached = present & -present;  // the lowest present bit's cube
  for (int grown = 0; grown != reached;) {
    grown = reached;
    for (int b = 0; b < 8; ++b)
      if (reached >> b & 1)
        for (const int flip : {1, 2, 4}) reached |= present & (1 << (b ^ flip));
  }
  return reached == present;
}

/// The hex mesh of the kept cubes: a cell per piece of each cube (one for a cube without pieces sought, or
/// whose samples are all outside), in grid order; a vertex per group of connected cells at each grid node,
/// numbered in grid order.
void build_cells(Lattice& L, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, const std::vector<unsigned char>& keep,
                 const std::vector<float>& winding) {
  const Eigen::Vector3i& dims = L.dims;
  Eigen::Matrix3Xd Q(3, V.cols());
  for (Eigen::Index v = 0; v < V.cols(); ++v) Q.col(v) = L.grid_coordinates(V.col(v));
  const PieceContext P{L, Q, F, keep, winding, L.samples};
  const std::vector<int> pieces_of = count_pieces(L, P, V);
  number_cells(L, keep, pieces_of);
  const FaceLinks links = link_faces(L, P, pieces_of);

  // Vertices: at each grid node, one per group of connected cells around it.
  const Eigen::Vector3i nd = dims + Eigen::Vector3i::Ones();
  L.mesh.type = CellType::hex8;
  L.mesh.cells.resize(8, static_cast<Eigen::Index>(L.cube_of_cell.size()));
  std::vector<Eigen::Vector3d> position;
  L.copies.clear();
  NodeCells at;
  std::vector<int> vertex_of_root;
  for (int k = 0; k < nd.z(); ++k)
    for (int j = 0; j < nd.y(); ++j)
      for (int i = 0; i < nd.x(); ++i) {
        at.cell.clear();
        at.corner.clear();
        at.bit.clear();
        at.clean = true;
        for (int b = 0; b < 8; ++b) {
          const int ci = i - 1 + (b & 1), cj = j - 1 + ((b >> 1) & 1), ck = k - 1 + ((b >> 2) & 1);
          int& c = at.cube_at[static_cast<std::size_t>(b)];
          c = -1;
          if (ci < 0 || cj < 0 || ck < 0 || ci >= dims.x() || cj >= dims.y() || ck >= dims.z()) continue;
          if (!keep[static_cast<std::size_t>(L.cube_index(ci, cj, ck))]) continue;
          c = L.cube_index(ci, cj, ck);
          at.clean = at.clean && !links.near_split[static_cast<std::size_t>(c)];
          const auto [first, last] = L.cells_of_cube(c);
          for (int cell = first; cell < last; ++cell) {
            at.cell.push_back(cell);
            at.corner.push_back(7 - b);  // the node is the cube's corner opposite its offset
            at.bit.push_back(b);
          }
        }
        if (at.cell.empty()) continue;
        for (std::size_t a = 1; a < at.cell.size() && at.clean && !links.part.empty(); ++a)
          at.clean = links.part[static_cast<std::size_t>(at.cell[a])] == links.part[static_cast<std::size_t>(at.cell[0])];
        if (at.clean && !links.part.empty()) at.clean = faces_join_around(at.cube_at);
        const Eigen::Vector3d x = L.origin + L.spacing * Eigen::Vector3d(i, j, k);
        const int n = static_cast<int>(at.cell.size());
        const std::size_t first_vertex = position.size();
        if (at.clean) {
          for (int a = 0; a < n; ++a)
            L.mesh.cells(at.corner[static_cast<std::size_t>(a)], at.cell[static_cast<std::size_t>(a)]) = static_cast<int>(first_vertex);
          position.push_back(x);
        } else {
          UnionFind groups = group_at_node(L, links, at);
          vertex_of_root.assign(static_cast<std::size_t>(n), -1);
          for (int a = 0; a < n; ++a) {
            int& v = vertex_of_root[static_cast<std::size_t>(groups.root(a))];
            if (v < 0) {
              v = static_cast<int>(position.size());
              position.push_back(x);
            }
            L.mesh.cells(at.corner[static_cast<std::size_t>(a)], at.cell[static_cast<std::size_t>(a)]) = v;
          }
        }
        const int here = static_cast<int>(position.size() - first_vertex);
        L.copies.insert(L.copies.end(), static_cast<std::size_t>(here), here);
      }
  L.mesh.vertices.resize(3, static_cast<Eigen::Index>(position.size()));
  for (std::size_t v = 0; v < position.size(); ++v) L.mesh.vertices.col(static_cast<Eigen::Index>(v)) = position[v];
}

}  // namespace

int Lattice::touched_slot(int cube) const {
  const auto it = std::lower_bound(touched.begin(), touched.end(), cube);
  return it != touched.end() && *it == cube ? static_cast<int>(it - touched.begin()) : -1;
}

std::pair<int, int> Lattice::cells_of_cube(int cube) const {
  const int first = cell_at[static_cast<std::size_t>(cube)];
  if (first < 0) return {0, 0};
  int last = first + 1;
  while (last < static_cast<int>(cube_of_cell.size()) && cube_of_cell[static_cast<std::size_t>(last)] == cube) ++last;
  return {first, last};
}

Eigen::Matrix3Xd Lattice::cell_samples(int cell) const {
  const int c = cube_of_cell[static_cast<std::size_t>(cell)], piece = piece_of_cell[static_cast<std::size_t>(cell)];
  const Eigen::Vector3i cube = cube_ijk(c);
  const int s = std::max(samples, 1), n = s * s * s, slot = touched_slot(c);
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < n; ++i) {
    if (slot >= 0 && samples > 0 &&
        sample_piece[static_cast<std::size_t>(slot) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)] != piece)
      continue;
    const Eigen::Vector3d abc(i % s + 0.5, (i / s) % s + 0.5, i / (s * s) + 0.5);
    out.push_back(origin + spacing * (cube.cast<double>() + abc / s));
  }
  Eigen::Matrix3Xd m(3, static_cast<Eigen::Index>(out.size()));
  for (std::size_t i = 0; i < out.size(); ++i) m.col(static_cast<Eigen::Index>(i)) = out[i];
  return m;
}

bool triangle_overlaps_cube(const std::array<Eigen::Vector3d, 3>& v, double e) {
  for (int a = 0; a < 3; ++a) {
    const double lo = std::min({v[0][a], v[1][a], v[2][a]}), hi = std::max({v[0][a], v[1][a], v[2][a]});
    if (lo > e || hi < -e) return false;
  }
  const auto separates = [&](const Eigen::Vector3d& axis) {
    const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
    const double r = e * axis.cwiseAbs().sum();
    return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
  };
  const std::array<Eigen::Vector3d, 3> edge = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  for (const Eigen::Vector3d& f : edge)
    for (int a = 0; a < 3; ++a)
      if (separates(Eigen::Vector3d::Unit(a).cross(f))) return false;
  return !separates(edge[0].cross(v[2] - v[0]));
}

bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // The endpoints on either side of (or on) the plane, and the line through the triangle: the signed volumes
  // of (p, q) with each edge share a sign (zeros allowed: touching counts).
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double dp = n.dot(p - a), dq = n.dot(q - a);
  if ((dp > 0.0 && dq > 0.0) || (dp < 0.0 && dq < 0.0) || (dp == 0.0 && dq == 0.0)) return false;
  const Eigen::Vector3d d = q - p;
  const double u = d.dot((a - p).cross(b - p)), v = d.dot((b - p).cross(c - p)), w = d.dot((c - p).cross(a - p));
  return (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0);
}

Lattice lattice_grid(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution) {
  if (resolution < 1) throw std::invalid_argument(fmt::format("lattice resolution must be >= 1, got {}", resolution));
  if (F.cols() == 0) throw std::invalid_argument("lattice of a surface with no triangles");
  check_triangles(V, F);
  return empty_grid(V, F, resolution);
}

Lattice lattice_on_grid(const Lattice& grid, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int samples) {
  if (samples < 0 || samples > 16)
    throw std::invalid_argument(fmt::format("lattice samples per cube edge must be 0 .. 16, got {}", samples));
  if (F.cols() == 0) throw std::invalid_argument("lattice of a surface with no triangles");
  if (!(grid.spacing > 0.0) || grid.dims.minCoeff() < 1)
    throw std::invalid_argument("lattice on a grid with no cubes (use lattice_grid)");
  check_triangles(V, F);
  Lattice L;
  L.origin = grid.origin;
  L.spacing = grid.spacing;
  L.dims = grid.dims;
  L.samples = samples;
  // Every cube a triangle meets (exact separating-axis tests), and every cube wholly inside.
  const std::vector<std::pair<int, int>> pairs = cube_triangle_pairs(L, V, F);
  std::vector<unsigned char> keep(static_cast<std::size_t>(L.dims.x()) * static_cast<std::size_t>(L.dims.y()) * static_cast<std::size_t>(L.dims.z()), 0);
  L.triangle.resize(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const int c = pairs[i].first;
    if (L.touched.empty() || L.touched.back() != c) {
      L.touched.push_back(c);
      L.triangle_start.push_back(static_cast<std::int64_t>(i));
    }
    keep[static_cast<std::size_t>(c)] = 1;
    L.triangle[i] = pairs[i].second;
  }
  L.triangle_start.push_back(static_cast<std::int64_t>(pairs.size()));
  const std::vector<float> winding = cube_windings(L, V, F, keep, edge_counts(F).open > 0);
  for (std::size_t c = 0; c < keep.size(); ++c) keep[c] = keep[c] || std::abs(winding[c]) > 0.5f;
  build_cells(L, V, F, keep, winding);
  return L;
}

Lattice lattice_for_surface(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution, int samples) {
  if (samples < 0 || samples > 16)
    throw std::invalid_argument(fmt::format("lattice samples per cube edge must be 0 .. 16, got {}", samples));
  return lattice_on_grid(lattice_grid(V, F, resolution), V, F, samples);
}

}  // namespace snh
