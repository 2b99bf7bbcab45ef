#include "snh/solve/multigrid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "snh/solve/direct_solver.hpp"

namespace snh {
namespace {

/// A level with at most this many free DOFs is solved directly.
constexpr Eigen::Index kCoarsestUnknowns = 3000;
/// Coarsening stops where it keeps more than this fraction of the unknowns (a lattice too thin to coarsen).
constexpr double kMinReduction = 0.6;
constexpr int kMaxLevels = 16;

/// Offset of hex corner k from corner 0 in lattice units (VolumeMesh's corner order).
Eigen::Vector3i corner_offset(int k) { return {k & 1, (k >> 1) & 1, (k >> 2) & 1}; }

/// A symmetric matrix in 3×3 nodal blocks, its lower triangle stored: row i's blocks (i, j ≤ i) at
/// start[i] .. start[i+1], columns sorted (the diagonal block last), values row-major (9 per block).
struct Blocks {
  std::vector<int> start{0}, col;
  std::vector<double> val;
  /// The slot of block (i, j); −1 if absent.
  [[nodiscard]] int find(int i, int j) const {
    const auto b = col.begin() + start[i], e = col.begin() + start[i + 1];
    const auto it = std::lower_bound(b, e, j);
    return it != e && *it == j ? static_cast<int>(it - col.begin()) : -1;
  }
  /// Sets the pattern from sorted, duplicate-free rows.
  void set_pattern(const std::vector<std::vector<int>>& rows_) {
    start.assign(1, 0);
    col.clear();
    for (const auto& r : rows_) {
      col.insert(col.end(), r.begin(), r.end());
      start.push_back(static_cast<int>(col.size()));
    }
    val.assign(9 * col.size(), 0.0);
  }
};

void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// A sparse node-to-node map with weights (prolongation W: fine node → coarse parents, or its transpose).
struct Weights {
  std::vector<int> start{0}, node;
  std::vector<double> weight;
};

Weights transpose(const Weights& w, int columns) {
  Weights t;
  t.start.assign(columns + 1, 0);
  for (int n : w.node) ++t.start[n + 1];
  for (int c = 0; c < columns; ++c) t.start[c + 1] += t.start[c];
  t.node.resize(w.node.size());
  t.weight.resize(w.node.size());
  std::vector<int> next(t.start.begin(), t.start.end() - 1);
  for (int r = 0; r + 1 < static_cast<int>(w.start.size()); ++r)
    for (int p = w.start[r]; p < w.start[r + 1]; ++p) {
      const int q = next[w.node[p]]++;
      t.node[q] = r;
      t.weight[q] = w.weight[p];
    }
  return t;
}

struct Level {
  int nodes = 0;
  std::vector<std::uint8_t> free;       ///< 3 per node
  std::vector<Eigen::Vector3i> at;      ///< lattice coordinates
  std::vector<int> piece;               ///< connected piece
  std::vector<std::array<int, 8>> cells;
  Blocks A;                             ///< masked: rows and columns of DOFs that are not free are zero
  std::vector<int> diagonal;            ///< per node, the slot of its diagonal block
  std::vector<double> inverse;          ///< 9 per node: the inverse of the free part of the diagonal block
  Weights down, up;                     ///< to the next level: parents of each node; children of each coarse node
  Eigen::VectorXd x, b, r;              ///< work vectors (3 per node)
  [[nodiscard]] Eigen::Index unknowns() const { return std::count(free.begin(), free.end(), std::uint8_t{1}); }
};

}  // namespace

LatticeCoordinates lattice_coordinates(const VolumeMesh& mesh) {
  if (mesh.type != CellType::hex8)
    throw std::invalid_argument(fmt::format("the multigrid solver (mg) needs a hexahedral lattice; this mesh has {} cells "
                                            "(use cholmod, ldlt or pcg)",
                                            to_string(mesh.type)));
  const Eigen::Index nv = mesh.vertex_count(), nc = mesh.cell_count();
  std::vector<int> start(nv + 1, 0), incident(8 * nc);
  for (Eigen::Index c = 0; c < nc; ++c)
    for (int k = 0; k < 8; ++k) {
      const int v = mesh.cells(k, c);
      if (v < 0 || v >= nv) throw std::invalid_argument(fmt::format("cell {}: vertex index {} is out of range", c, v));
      ++start[v + 1];
    }
  for (Eigen::Index v = 0; v < nv; ++v) start[v + 1] += start[v];
  {
    std::vector<int> next(start.begin(), start.end() - 1);
    for (Eigen::Index c = 0; c < nc; ++c)
      for (int k = 0; k < 8; ++k) incident[next[mesh.cells(k, c)]++] = static_cast<int>(c);
  }
  LatticeCoordinates out;
  out.coordinates = Eigen::Matrix3Xi::Zero(3, nv);
  out.piece.assign(nv, -1);
  std::vector<std::uint8_t> queued(nc, 0);
  std::vector<int> queue;
  int pieces = 0;
  for (Eigen::Index seed = 0; seed < nc; ++seed) {
    if (queued[seed]) continue;
    const int piece = pieces++;
    out.piece[mesh.cells(0, seed)] = piece;  // at (0, 0, 0)
    queue.assign(1, static_cast<int>(seed));
    queued[seed] = 1;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int c = queue[q];
      int known = 0;
      while (out.piece[mesh.cells(known, c)] < 0) ++known;  // a corner placed by the cell that queued c
      const Eigen::Vector3i origin = out.coordinates.col(mesh.cells(known, c)) - corner_offset(known);
      for (int k = 0; k < 8; ++k) {
        const int v = mesh.cells(k, c);
        const Eigen::Vector3i p = origin + corner_offset(k);
        if (out.piece[v] >= 0) {
          if (out.coordinates.col(v) != p)
            throw std::invalid_argument(fmt::format(
                "the multigrid solver (mg) needs a hexahedral lattice: cell {} places vertex {} at lattice point ({}, {}, {}) "
                "where its neighbours put it at ({}, {}, {})",
                c, v, p.x(), p.y(), p.z(), out.coordinates(0, v), out.coordinates(1, v), out.coordinates(2, v)));
          continue;
        }
        out.piece[v] = piece;
        out.coordinates.col(v) = p;
        for (int i = start[v]; i < start[v + 1]; ++i)
          if (!queued[incident[i]]) {
            queued[incident[i]] = 1;
            queue.push_back(incident[i]);
          }
      }
    }
  }
  for (Eigen::Index v = 0; v < nv; ++v)
    if (out.piece[v] < 0) out.piece[v] = pieces++;
  // Each piece from 0 (so that halving keeps even coordinates even).
  std::vector<Eigen::Vector3i> low(pieces, Eigen::Vector3i::Constant(std::numeric_limits<int>::max()));
  for (Eigen::Index v = 0; v < nv; ++v) low[out.piece[v]] = low[out.piece[v]].cwiseMin(out.coordinates.col(v));
  for (Eigen::Index v = 0; v < nv; ++v) out.coordinates.col(v) -= low[out.piece[v]];
  return out;
}

/// A fingerprint of a sparse matrix's pattern (its size and index arrays, FNV-1a), to tell a new pattern from
/// the last without keeping a copy (a collision is caught by values()' check of every block it fills).
std::uint64_t pattern_hash(const SparseLower& A) {
  std::uint64_t h = 1469598103934665603ull;
  const auto mix = [&h](std::uint64_t v) { h = (h ^ v) * 1099511628211ull; };
  mix(static_cast<std::uint64_t>(A.rows()));
  mix(static_cast<std::uint64_t>(A.nonZeros()));
  for (Eigen::Index c = 0; c <= A.outerSize(); ++c) mix(static_cast<std::uint64_t>(A.outerIndexPtr()[c]));
  for (Eigen::Index k = 0; k < A.nonZeros(); ++k) mix(static_cast<std::uint64_t>(A.innerIndexPtr()[k]));
  return h;
}

struct MultigridPreconditioner::Impl {
  std::vector<Level> levels;
  std::vector<int> row_dof;  ///< free row → DOF of level 0 (3 v + axis)
  bool have_structure = false;
  std::uint64_t pattern = 0;  ///< pattern_hash of the A the structure was built for
  std::vector<int> cursor;  ///< work: a slot per node
  // The coarsest level as a scalar matrix for the direct solver.
  std::vector<int> coarse_dof;    ///< its free DOFs (3 node + axis)
  std::vector<int> coarse_value;  ///< per stored entry of `coarse`, its index in the last level's A.val
  SparseLower coarse;
  std::unique_ptr<LinearSolver> direct = make_ldlt_solver();  // small: no BLAS (its buffers and threads) needed
  Eigen::VectorXd coarse_b;
  std::vector<double> row;  ///< work: one block row of A W (9 per coarse node)
  std::vector<int> touched, where_coarse;

  Impl(const VolumeMesh& mesh, const std::vector<int>& free_index);
  void coarsen();
  void structure(const SparseLower& A);
  bool values(const SparseLower& A, double shift);
  void galerkin(Level& fine, Level& coarse_level);
  void vcycle(std::size_t l);
  void product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap);
  Eigen::VectorXd product_in, product_out;
};

MultigridPreconditioner::Impl::Impl(const VolumeMesh& mesh, const std::vector<int>& free_index) {
  const LatticeCoordinates lattice = lattice_coordinates(mesh);
  Level L;
  L.nodes = static_cast<int>(mesh.vertex_count());
  if (free_index.size() != 3 * static_cast<std::size_t>(L.nodes))
    throw std::invalid_argument(fmt::format("multigrid: {} DOF indices for {} vertices", free_index.size(), L.nodes));
  L.free.resize(free_index.size());
  int free_count = 0;
  for (std::size_t d = 0; d < free_index.size(); ++d) {
    L.free[d] = free_index[d] >= 0;
    free_count = std::max(free_count, free_index[d] + 1);
  }
  row_dof.assign(free_count, -1);
  for (std::size_t d = 0; d < free_index.size(); ++d)
    if (free_index[d] >= 0) row_dof[free_index[d]] = static_cast<int>(d);
  L.at.resize(L.nodes);
  L.piece = lattice.piece;
  for (int v = 0; v < L.nodes; ++v) L.at[v] = lattice.coordinates.col(v);
  L.cells.resize(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int k = 0; k < 8; ++k) L.cells[c][k] = mesh.cells(k, c);
  levels.push_back(std::move(L));
  while (levels.size() < kMaxLevels && levels.back().unknowns() > kCoarsestUnknowns) {
    const Eigen::Index before = levels.back().unknowns();
    coarsen();
    if (levels.back().unknowns() > kMinReduction * static_cast<double>(before) || levels.back().unknowns() == 0) {
      levels.pop_back();
      levels.back().down = levels.back().up = Weights{};
      break;
    }
  }
  for (Level& l : levels) {
    l.x.resize(3 * l.nodes);
    l.b.resize(3 * l.nodes);
    l.r.resize(3 * l.nodes);
  }
}

/// Appends the level of twice the cell size: its cubes, nodes (in grid order), free DOFs, and the
/// trilinear prolongation from it.
void MultigridPreconditioner::Impl::coarsen() {
  Level& F = levels.back();
  Level C;
  using Key = std::array<int, 4>;  // piece, z, y, x: sorted in grid order
  std::map<Key, int> cube, node;
  for (const auto& cell : F.cells) {
    const Eigen::Vector3i q = F.at[cell[0]] / 2;  // coordinates are ≥ 0
    cube.emplace(Key{F.piece[cell[0]], q.z(), q.y(), q.x()}, 0);
  }
  for (const auto& [key, unused] : cube)
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3i o = corner_offset(k);
      node.emplace(Key{key[0], key[1] + o.z(), key[2] + o.y(), key[3] + o.x()}, 0);
    }
  C.nodes = 0;
  for (auto& [key, index] : node) {
    index = C.nodes++;
    C.at.emplace_back(key[3], key[2], key[1]);
    C.piece.push_back(key[0]);
  }
  for (const auto& [key, unused] : cube) {
    std::array<int, 8> corners{};
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3i o = corner_offset(k);
      corners[k] = node.at(Key{key[0], key[1] + o.z(), key[2] + o.y(), key[3] + o.x()});
    }
    C.cells.push_back(corners);
  }
  // Trilinear weights: an even coordinate 2a is coarse a, an odd one 2a+1 halfway between a and a+1. Nodes of
  // no cell (pieces of their own) have no parent.
  std::vector<std::uint8_t> in_cell(F.nodes, 0);
  for (const auto& cell : F.cells)
    for (int v : cell) in_cell[v] = 1;
  std::vector<int> coincident(C.nodes, -1);
  for (int v = 0; v < F.nodes; ++v) {
    if (in_cell[v]) {
      const Eigen::Vector3i& a = F.at[v];
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3i o = corner_offset(k);
        double w = 1.0;
        Eigen::Vector3i p;
        bool skip = false;
        for (int d = 0; d < 3; ++d) {
          if (a[d] % 2 == 0) {
            if (o[d]) skip = true;
            p[d] = a[d] / 2;
          } else {
            p[d] = a[d] / 2 + o[d];
            w *= 0.5;
          }
        }
        if (skip) continue;
        const int parent = node.at(Key{F.piece[v], p.z(), p.y(), p.x()});
        F.down.node.push_back(parent);
        F.down.weight.push_back(w);
        if (w == 1.0) coincident[parent] = v;
      }
    }
    F.down.start.push_back(static_cast<int>(F.down.node.size()));
  }
  F.up = transpose(F.down, C.nodes);
  // A coarse DOF is free where it reaches a free fine DOF and the fine vertex at its place (if any) is free there.
  C.free.assign(3 * static_cast<std::size_t>(C.nodes), 0);
  for (int n = 0; n < C.nodes; ++n)
    for (int a = 0; a < 3; ++a) {
      bool reaches = false;
      for (int p = F.up.start[n]; p < F.up.start[n + 1]; ++p) reaches = reaches || F.free[3 * F.up.node[p] + a];
      C.free[3 * n + a] = reaches && (coincident[n] < 0 || F.free[3 * coincident[n] + a]);
    }
  levels.push_back(std::move(C));
}

/// The block patterns for A's pattern: level 0 from A, each coarse level's as Wᵀ A W, and the coarsest
/// level's scalar matrix.
void MultigridPreconditioner::Impl::structure(const SparseLower& A) {
  Level& L0 = levels.front();
  {
    // Column c of A's lower triangle holds rows r ≥ c: node pairs (i ≥ j), collected per node j.
    std::vector<std::vector<int>> rows(L0.nodes);
    std::vector<int> below;
    for (Eigen::Index c = 0; c < A.outerSize();) {
      const int j = row_dof[c] / 3;
      below.clear();
      for (; c < A.outerSize() && row_dof[c] / 3 == j; ++c)
        for (SparseLower::InnerIterator it(A, c); it; ++it) below.push_back(row_dof[it.row()] / 3);
      sort_unique(below);
      for (int i : below)
        if (i != j) rows[i].push_back(j);  // j ascending: rows stay sorted
    }
    for (int i = 0; i < L0.nodes; ++i) rows[i].push_back(i);
    L0.A.set_pattern(rows);
  }
  cursor.assign(L0.nodes, 0);
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) {
    Level &F = levels[l], &C = levels[l + 1];
    // Block (i, k ≤ i) reaches the coarse pairs (I, K), I a parent of i and K of k, stored at (max, min).
    std::vector<std::vector<int>> coarse_rows(C.nodes);
    std::vector<int> reach;
    for (int i = 0; i < F.nodes; ++i) {
      reach.clear();
      for (int s = F.A.start[i]; s < F.A.start[i + 1]; ++s) {
        const int k = F.A.col[s];
        reach.insert(reach.end(), F.down.node.begin() + F.down.start[k], F.down.node.begin() + F.down.start[k + 1]);
      }
      sort_unique(reach);
      for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
        const int I = F.down.node[p];
        for (int K : reach) coarse_rows[std::max(I, K)].push_back(std::min(I, K));
      }
    }
    for (int I = 0; I < C.nodes; ++I) {
      coarse_rows[I].push_back(I);
      sort_unique(coarse_rows[I]);
    }
    C.A.set_pattern(coarse_rows);
  }
  for (Level& l : levels) {
    l.diagonal.resize(l.nodes);
    for (int i = 0; i < l.nodes; ++i) l.diagonal[i] = l.A.find(i, i);
    l.inverse.assign(9 * static_cast<std::size_t>(l.nodes), 0.0);
  }
  // The coarsest level's free DOFs as a lower-triangular scalar matrix (column c: rows r ≥ c in order).
  const Level& K = levels.back();
  std::vector<int> index(3 * static_cast<std::size_t>(K.nodes), -1);
  coarse_dof.clear();
  for (int d = 0; d < 3 * K.nodes; ++d)
    if (K.free[d]) {
      index[d] = static_cast<int>(coarse_dof.size());
      coarse_dof.push_back(d);
    }
  const int n = static_cast<int>(coarse_dof.size());
  struct Entry {
    int c, r, value;
  };
  std::vector<Entry> entries;  // A(i a, j b) = block (i, j)'s entry (a, b), i ≥ j
  for (int i = 0; i < K.nodes; ++i)
    for (int s = K.A.start[i]; s < K.A.start[i + 1]; ++s) {
      const int j = K.A.col[s];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const int r = index[3 * i + a], c = index[3 * j + b];
          if (r >= 0 && c >= 0 && r >= c) entries.push_back({c, r, 9 * s + 3 * a + b});
        }
    }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) { return x.c != y.c ? x.c < y.c : x.r < y.r; });
  std::vector<int> outer(n + 1, 0), inner;
  coarse_value.clear();
  for (const Entry& e : entries) {
    ++outer[e.c + 1];
    inner.push_back(e.r);
    coarse_value.push_back(e.value);
  }
  for (int c = 0; c < n; ++c) outer[c + 1] += outer[c];
  coarse = SparseLower(n, n);
  coarse.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), coarse.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), coarse.innerIndexPtr());
  coarse_b.resize(n);
}

/// The next level's A from this one's, Wᵀ A W, one fine block row at a time: the row's part of A W (A's
/// diagonal blocks halved) spread to the row's parents I, each product Y for the coarse pair (I, K) stored
/// as Y at (I, K) below the diagonal, Yᵀ at (K, I) above it, Y + Yᵀ on it (A is symmetric); then the coarse
/// DOFs that are not free masked out.
void MultigridPreconditioner::Impl::galerkin(Level& F, Level& C) {
  std::fill(C.A.val.begin(), C.A.val.end(), 0.0);
  row.assign(9 * static_cast<std::size_t>(C.nodes), 0.0);
  where_coarse.assign(C.nodes, -1);
  for (int i = 0; i < F.nodes; ++i) {
    touched.clear();
    for (int s = F.A.start[i]; s < F.A.start[i + 1]; ++s) {
      const int k = F.A.col[s];
      const double* a = &F.A.val[9 * static_cast<std::size_t>(s)];
      const double half = k == i ? 0.5 : 1.0;
      for (int p = F.down.start[k]; p < F.down.start[k + 1]; ++p) {
        const int K = F.down.node[p];
        double* t = &row[9 * static_cast<std::size_t>(K)];
        if (where_coarse[K] < 0) {
          where_coarse[K] = 0;
          touched.push_back(K);
        }
        const double w = half * F.down.weight[p];
        for (int e = 0; e < 9; ++e) t[e] += w * a[e];
      }
    }
    std::sort(touched.begin(), touched.end());  // a fixed order of the sums below
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
      const int I = F.down.node[p];
      const double w = F.down.weight[p];
      int s = C.A.start[I];
      for (int K : touched) {
        const double* t = &row[9 * static_cast<std::size_t>(K)];
        if (K <= I) {
          while (C.A.col[s] < K) ++s;  // both sorted; every K ≤ I reached from i is in row I
          double* c = &C.A.val[9 * static_cast<std::size_t>(s)];
          if (K < I) {
            for (int e = 0; e < 9; ++e) c[e] += w * t[e];
          } else {
            for (int a = 0; a < 3; ++a)
              for (int b = 0; b < 3; ++b) c[3 * a + b] += w * (t[3 * a + b] + t[3 * b + a]);
          }
        } else {
          double* c = &C.A.val[9 * static_cast<std::size_t>(C.A.find(K, I))];
          for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) c[3 * a + b] += w * t[3 * b + a];
        }
      }
    }
    for (int K : touched) {
      std::fill_n(&row[9 * static_cast<std::size_t>(K)], 9, 0.0);
      where_coarse[K] = -1;
    }
  }
  for (int I = 0; I < C.nodes; ++I)
    for (int s = C.A.start[I]; s < C.A.start[I + 1]; ++s) {
      const int J = C.A.col[s];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          if (!C.free[3 * I + a] || !C.free[3 * J + b]) C.A.val[9 * static_cast<std::size_t>(s) + 3 * a + b] = 0.0;
    }
}

bool MultigridPreconditioner::Impl::values(const SparseLower& A, double shift) {
  Level& L0 = levels.front();
  // Column c (DOF b of node j) of A's lower triangle: entry (i a, j b), i ≥ j, is block (i, j)'s entry (a, b).
  // Columns come in increasing j, so each row's cursor only moves forward to block (i, j).
  const double* v = A.valuePtr();
  std::copy(L0.A.start.begin(), L0.A.start.end() - 1, cursor.begin());
  for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
    const int dc = row_dof[c], j = dc / 3, b = dc % 3;
    for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k) {
      const int dr = row_dof[A.innerIndexPtr()[k]], i = dr / 3;
      while (L0.A.col[cursor[i]] < j) ++cursor[i];  // stops at the diagonal block (i ≥ j) at the latest
      if (L0.A.col[cursor[i]] != j) throw std::logic_error("multigrid: the matrix's pattern changed unnoticed");
      L0.A.val[9 * static_cast<std::size_t>(cursor[i]) + 3 * (dr % 3) + b] = v[k];
    }
  }
  // The upper halves of the diagonal blocks by symmetry, and the shift.
  for (int i = 0; i < L0.nodes; ++i) {
    double* d = &L0.A.val[9 * static_cast<std::size_t>(L0.diagonal[i])];
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b) d[3 * a + b] = d[3 * b + a];
    for (int a = 0; a < 3; ++a)
      if (L0.free[3 * i + a]) d[4 * a] += shift;
  }
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) galerkin(levels[l], levels[l + 1]);
  // Inverses of the diagonal blocks' free parts (Cholesky: a block that is not positive definite proves A is not).
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) {
    Level& L = levels[l];
    for (int i = 0; i < L.nodes; ++i) {
      Eigen::Matrix3d D = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&L.A.val[9 * static_cast<std::size_t>(L.diagonal[i])]);
      for (int a = 0; a < 3; ++a)
        if (!L.free[3 * i + a]) D(a, a) = 1.0;
      const Eigen::LLT<Eigen::Matrix3d> llt(D);
      if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().array() > 0.0).all()) return false;
      Eigen::Matrix3d inv = llt.solve(Eigen::Matrix3d::Identity());
      for (int a = 0; a < 3; ++a)
        if (!L.free[3 * i + a]) inv.row(a).setZero(), inv.col(a).setZero();
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&L.inverse[9 * static_cast<std::size_t>(i)]) = inv;
    }
  }
  const Level& K = levels.back();
  for (std::size_t e = 0; e < coarse_value.size(); ++e) coarse.valuePtr()[e] = K.A.val[coarse_value[e]];
  return coarse.rows() == 0 || direct->try_factorize(coarse);
}

namespace {

/// y −= a x for a row-major 3×3 block a; yt −= aᵀ x.
inline void subtract(const double* a, const double* x, double* y) {
  y[0] -= a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
  y[1] -= a[3] * x[0] + a[4] * x[1] + a[5] * x[2];
  y[2] -= a[6] * x[0] + a[7] * x[1] + a[8] * x[2];
}
inline void subtract_transposed(const double* a, const double* x, double* y) {
  y[0] -= a[0] * x[0] + a[3] * x[1] + a[6] * x[2];
  y[1] -= a[1] * x[0] + a[4] * x[1] + a[7] * x[2];
  y[2] -= a[2] * x[0] + a[5] * x[1] + a[8] * x[2];
}

/// x_i = D_i⁻¹ s for node i.
inline void solve_diagonal(const Level& L, int i, const double* s, double* x) {
  const double* d = &L.inverse[9 * static_cast<std::size_t>(i)];
  x[0] = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
  x[1] = d[3] * s[0] + d[4] * s[1] + d[5] * s[2];
  x[2] = d[6] * s[0] + d[7] * s[1] + d[8] * s[2];
}

/// A forward nodal-block Gauss–Seidel sweep for L.A x = L.b from x = 0 (the blocks above the diagonal meet
/// only zeros).
void forward_sweep(Level& L) {
  L.x.setZero();
  const double* val = L.A.val.data();
  double* x = L.x.data();
  for (int i = 0; i < L.nodes; ++i) {
    double s[3] = {L.b[3 * i], L.b[3 * i + 1], L.b[3 * i + 2]};
    for (int k = L.A.start[i]; k + 1 < L.A.start[i + 1]; ++k) subtract(val + 9 * static_cast<std::size_t>(k), x + 3 * L.A.col[k], s);
    solve_diagonal(L, i, s, x + 3 * i);
  }
}

/// A backward nodal-block Gauss–Seidel sweep on L.x: row i's blocks left of the diagonal meet the old x,
/// the (transposed) blocks right of it the new values, gathered in L.r as each row is done.
void backward_sweep(Level& L) {
  L.r.setZero();
  const double* val = L.A.val.data();
  double* x = L.x.data();
  double* later = L.r.data();
  for (int i = L.nodes - 1; i >= 0; --i) {
    const int end = L.A.start[i + 1] - 1;  // the diagonal block
    double s[3] = {L.b[3 * i] + later[3 * i], L.b[3 * i + 1] + later[3 * i + 1], L.b[3 * i + 2] + later[3 * i + 2]};
    for (int k = L.A.start[i]; k < end; ++k) subtract(val + 9 * static_cast<std::size_t>(k), x + 3 * L.A.col[k], s);
    solve_diagonal(L, i, s, x + 3 * i);
    for (int k = L.A.start[i]; k < end; ++k)
      subtract_transposed(val + 9 * static_cast<std::size_t>(k), x + 3 * i, later + 3 * L.A.col[k]);
  }
}

/// y = b − A x with A's lower block triangle (b may be null: y = −A x).
void subtract_product(const Level& L, const double* x, const double* b, double* y) {
  const double* val = L.A.val.data();
  for (int d = 0; d < 3 * L.nodes; ++d) y[d] = b ? b[d] : 0.0;
  for (int i = 0; i < L.nodes; ++i) {
    const int end = L.A.start[i + 1] - 1;
    for (int k = L.A.start[i]; k < end; ++k) {
      const double* a = val + 9 * static_cast<std::size_t>(k);
      const int j = L.A.col[k];
      subtract(a, x + 3 * j, y + 3 * i);
      subtract_transposed(a, x + 3 * i, y + 3 * j);
    }
    subtract(val + 9 * static_cast<std::size_t>(end), x + 3 * i, y + 3 * i);
  }
}

}  // namespace

void MultigridPreconditioner::Impl::vcycle(std::size_t l) {
  Level& L = levels[l];
  if (l + 1 == levels.size()) {
    for (std::size_t k = 0; k < coarse_dof.size(); ++k) coarse_b[static_cast<Eigen::Index>(k)] = L.b[coarse_dof[k]];
    L.x.setZero();
    if (coarse_b.size() == 0) return;
    const Eigen::VectorXd y = direct->solve(coarse_b);
    for (std::size_t k = 0; k < coarse_dof.size(); ++k) L.x[coarse_dof[k]] = y[static_cast<Eigen::Index>(k)];
    return;
  }
  Level& C = levels[l + 1];
  forward_sweep(L);
  subtract_product(L, L.x.data(), L.b.data(), L.r.data());
  // Restriction Wᵀ r on the coarse free DOFs.
  for (int I = 0; I < C.nodes; ++I) {
    double r0 = 0.0, r1 = 0.0, r2 = 0.0;
    for (int p = L.up.start[I]; p < L.up.start[I + 1]; ++p) {
      const int i = L.up.node[p];
      const double w = L.up.weight[p];
      r0 += w * L.r[3 * i];
      r1 += w * L.r[3 * i + 1];
      r2 += w * L.r[3 * i + 2];
    }
    C.b[3 * I] = C.free[3 * I] ? r0 : 0.0;
    C.b[3 * I + 1] = C.free[3 * I + 1] ? r1 : 0.0;
    C.b[3 * I + 2] = C.free[3 * I + 2] ? r2 : 0.0;
  }
  vcycle(l + 1);
  // Prolongation W e on the fine free DOFs.
  for (int i = 0; i < L.nodes; ++i)
    for (int p = L.down.start[i]; p < L.down.start[i + 1]; ++p) {
      const int I = L.down.node[p];
      const double w = L.down.weight[p];
      for (int a = 0; a < 3; ++a)
        if (L.free[3 * i + a]) L.x[3 * i + a] += w * C.x[3 * I + a];
    }
  backward_sweep(L);
}

MultigridPreconditioner::MultigridPreconditioner(const VolumeMesh& mesh, const std::vector<int>& free_index)
    : impl_(std::make_unique<Impl>(mesh, free_index)) {}

MultigridPreconditioner::~MultigridPreconditioner() = default;

bool MultigridPreconditioner::compute(const SparseLower& A, double shift) {
  if (A.rows() != static_cast<Eigen::Index>(impl_->row_dof.size()) || A.cols() != A.rows())
    throw std::invalid_argument(fmt::format("multigrid: a {}x{} matrix for {} free DOFs", A.rows(), A.cols(), impl_->row_dof.size()));
  const std::uint64_t pattern = pattern_hash(A);
  if (!impl_->have_structure || pattern != impl_->pattern) {
    impl_->structure(A);
    impl_->pattern = pattern;
    impl_->have_structure = true;
  }
  return impl_->values(A, shift);
}

void MultigridPreconditioner::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) const { impl_->product(p, Ap); }

void MultigridPreconditioner::Impl::product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) {
  const Level& L0 = levels.front();
  product_in.setZero(3 * L0.nodes);
  for (std::size_t k = 0; k < row_dof.size(); ++k) product_in[row_dof[k]] = p[static_cast<Eigen::Index>(k)];
  product_out.resize(3 * L0.nodes);
  subtract_product(L0, product_in.data(), nullptr, product_out.data());
  Ap.resize(p.size());
  for (std::size_t k = 0; k < row_dof.size(); ++k) Ap[static_cast<Eigen::Index>(k)] = -product_out[row_dof[k]];
}

void MultigridPreconditioner::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  Level& L0 = impl_->levels.front();
  L0.b.setZero();
  const auto& rows = impl_->row_dof;
  for (std::size_t k = 0; k < rows.size(); ++k) L0.b[rows[k]] = r[static_cast<Eigen::Index>(k)];
  impl_->vcycle(0);
  z.resize(r.size());
  for (std::size_t k = 0; k < rows.size(); ++k) z[static_cast<Eigen::Index>(k)] = L0.x[rows[k]];
}

int MultigridPreconditioner::levels() const { return static_cast<int>(impl_->levels.size()); }

Eigen::Index MultigridPreconditioner::unknowns(int level) const { return impl_->levels.at(level).unknowns(); }

namespace {

class MultigridSolver final : public LinearSolver {
 public:
  MultigridSolver(const LinearSolverOptions& o, const SolverGeometry& g) : tolerance_(o.tolerance), vcycle_(mesh_of(g), *g.free_index) {}
  bool try_factorize(const SparseLower& A) override { return vcycle_.compute(A); }
  double factorize(const SparseLower& A) override {
    if (vcycle_.compute(A)) return 0.0;
    // As the direct solvers: a shift doubling from 1e-10 of the largest diagonal entry, up to Gershgorin's bound.
    Eigen::VectorXd row_abs = Eigen::VectorXd::Zero(A.rows());
    for (Eigen::Index c = 0; c < A.outerSize(); ++c)
      for (SparseLower::InnerIterator it(A, c); it; ++it) {
        row_abs[it.row()] += std::abs(it.value());
        if (it.row() != it.col()) row_abs[it.col()] += std::abs(it.value());
      }
    const double bound = 2.0 * std::max(row_abs.size() ? row_abs.maxCoeff() : 0.0, 1e-300);
    for (double shift = 1e-10 * std::max(A.diagonal().cwiseAbs().maxCoeff(), 1e-300); std::isfinite(bound) && shift <= 2.0 * bound;
         shift *= 2.0)
      if (vcycle_.compute(A, shift)) return shift;
    throw std::runtime_error("mg: the Newton matrix could not be made positive definite by a diagonal shift (it has a non-finite entry)");
  }
  /// Conjugate gradients on the matrix the V-cycle holds (A, plus the shift factorize() added).
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, b.size() / 10));
    Eigen::VectorXd x;
    const MatrixProduct A = [this](const Eigen::VectorXd& p, Eigen::VectorXd& Ap) { vcycle_.multiply(p, Ap); };
    const CgResult r = conjugate_gradients(A, b, vcycle_, std::max(tolerance_ * b.norm(), enough), max_iterations, x);
    iterations_ = r.iterations;
    return r.status == CgStatus::converged ? x : Eigen::VectorXd::Constant(b.size(), std::nan(""));
  }
  int last_iterations() const override { return iterations_; }
  std::string_view name() const override { return "mg"; }
  bool inexact() const override { return true; }

 private:
  static const VolumeMesh& mesh_of(const SolverGeometry& g) {
    if (!g.mesh || !g.free_index)
      throw std::invalid_argument("the multigrid solver (mg) needs the mesh behind the matrix (use cholmod, ldlt or pcg)");
    return *g.mesh;
  }
  double tolerance_;
  MultigridPreconditioner vcycle_;
  int iterations_ = 0;
};

}  // namespace

std::unique_ptr<LinearSolver> make_multigrid_solver(const LinearSolverOptions& options, const SolverGeometry& geometry) {
  return std::make_unique<MultigridSolver>(options, geometry);
}

}  // namespace snh
