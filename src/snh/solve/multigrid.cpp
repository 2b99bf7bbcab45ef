#include "snh/solve/multigrid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>

#ifdef __AVX__
#include <immintrin.h>
#endif

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <fmt/format.h>

#include "snh/solve/direct_solver.hpp"

namespace snh {
namespace {

/// A level with at most this many free DOFs is solved directly: lattice levels (sparse: 81 blocks per node
/// at most), and aggregation's (whose coarse operators are much denser, their factor nearly full).
constexpr Eigen::Index kCoarsestUnknowns = 3000;
constexpr Eigen::Index kCoarsestAggregationUnknowns = 500;
/// Coarsening stops where it keeps more than this fraction of the unknowns (a lattice too thin to coarsen).
constexpr double kMinReduction = 0.6;
constexpr int kMaxLevels = 16;

/// Offset of hex corner k from corner 0 in lattice units (VolumeMesh's corner order).
Eigen::Vector3i corner_offset(int k) { return {k & 1, (k >> 1) & 1, (k >> 2) & 1}; }

using Block3 = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
using ConstBlock3 = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;

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
    val.assign(9 * col.size() + 1, 0.0);  // one more: subtract_product() reads 4 doubles from a block's last row
  }
};

void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// A prolongation P from a coarse level to a fine one in 3×3 blocks: per fine node, its coarse parents I with
/// the block P_iI (row-major, 9 per entry). The lattice's trilinear weights are multiples of the identity;
/// smoothed aggregation's blocks are full.
struct Transfer {
  std::vector<int> start{0}, node;
  std::vector<double> block;
  std::vector<double> weight;  ///< the lattice's: block = weight·I, the V-cycle's transfers read these (a ninth
                               ///< of the bytes; the same sums: the blocks' zeros add nothing); empty otherwise
  void push(int parent, const double* b) {
    node.push_back(parent);
    block.insert(block.end(), b, b + 9);
  }
};

struct Level {
  int nodes = 0;
  std::vector<std::uint8_t> free;       ///< 3 per node
  // The lattice's (geometric coarsening):
  std::vector<Eigen::Vector3i> at;      ///< lattice coordinates
  std::vector<int> piece;               ///< connected piece
  std::vector<std::array<int, 8>> cells;
  // Smoothed aggregation's:
  std::vector<double> near_null;        ///< 18 per node: the rigid-body modes' rows (3×6, row-major)
  std::vector<int> aggregate;           ///< per node, its aggregate (−1: a node with no free DOF)
  std::vector<double> tentative;        ///< 18 per node: its rows of the tentative prolongator (3×6)
  std::vector<int> full_start, full_slot;  ///< per node, every block of its row (both triangles), by slot
  std::vector<int> full_node;           ///< … and the column node (> row: the stored block is (col, row)ᵀ)
  Blocks A;                             ///< masked: rows and columns of DOFs that are not free are zero
  std::vector<int> diagonal;            ///< per node, the slot of its diagonal block
  std::vector<double> inverse;          ///< 9 per node: the inverse of the free part of the diagonal block
  Transfer down;                        ///< P to the next level: the parents of each node
  std::vector<int> up_start, up_entry, up_fine;  ///< Pᵀ: per node of the next level, the entries of `down`
                                                 ///< that reach it and their fine nodes
  // The smoother's colouring and block rows (sweep_rows()): no two coupled nodes share a colour; each node's
  // off-diagonal blocks, both triangles, sorted by (colour, column node), the first `before` of them of
  // lower colours, each a slot of A (to copy its values from) and the column node. A lexicographic level
  // (one that runs on one thread) sorts them by column node alone: the first `before` are those of lower nodes.
  bool lexicographic = false;
  std::vector<int> colour;              ///< per node
  std::vector<int> colour_start, by_colour;  ///< the nodes of each colour, ascending
  std::vector<int> row_start, row_end;   ///< per node, its blocks' range; rows lie in sweep order (by colour,
                                         ///< or by node on a lexicographic level) so that a sweep streams them
  std::vector<int> row_slot, row_node, before;
  std::vector<float> row_val;           ///< the blocks A_ik of those rows, 9 each by columns (column-major), as
                                        ///< the rows lie, in single precision (half the memory traffic; the
                                        ///< smoother's alone), and 3 more floats (read, never used: subtract_row)
  // The product A x by a fixed number of row chunks (not the thread count): each chunk's rows i sum their
  // blocks (i, k ≤ i) and spill the transposed ones into the chunk's own buffer, rows chunk_low .. its end.
  std::vector<int> chunk_start, chunk_low;
  std::vector<std::size_t> chunk_offset;  ///< each chunk's buffer in `spill` (3 per node)
  std::vector<double> spill;
  Eigen::VectorXd x, b, r;              ///< work vectors (3 per node)
  Eigen::VectorXd power;                ///< aggregation: the last power iteration's vector for ρ(D⁻¹ A)
  [[nodiscard]] Eigen::Index unknowns() const { return std::count(free.begin(), free.end(), std::uint8_t{1}); }
  [[nodiscard]] bool has_free(int i) const { return free[3 * i] || free[3 * i + 1] || free[3 * i + 2]; }
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
/// the last without keeping a copy (a collision, at odds of about 2⁻⁶⁴, is caught only where the entry count
/// differs: values() then finds value_slot the wrong length). The index arrays go through four interleaved
/// FNV-1a streams, combined at the end: one stream is a chain of dependent multiplications (Figure 1's 6.4 million entries: 6.2 ms per V-cycle set-up with one stream,
/// 2.7 ms with four).
std::uint64_t pattern_hash(const SparseLower& A) {
  constexpr std::uint64_t kBasis = 1469598103934665603ull, kPrime = 1099511628211ull;
  std::uint64_t h[4] = {kBasis, kBasis ^ 1, kBasis ^ 2, kBasis ^ 3};
  const auto mix = [](std::uint64_t& to, std::uint64_t v) { to = (to ^ v) * kPrime; };
  const auto stream = [&](const int* p, Eigen::Index n) {
    Eigen::Index k = 0;
    for (; k + 4 <= n; k += 4)
      for (int s = 0; s < 4; ++s) mix(h[s], static_cast<std::uint32_t>(p[k + s]));
    for (; k < n; ++k) mix(h[0], static_cast<std::uint32_t>(p[k]));
  };
  mix(h[0], static_cast<std::uint64_t>(A.rows()));
  mix(h[1], static_cast<std::uint64_t>(A.nonZeros()));
  stream(A.outerIndexPtr(), A.outerSize() + 1);
  stream(A.innerIndexPtr(), A.nonZeros());
  std::uint64_t out = kBasis;
  for (const std::uint64_t v : h) mix(out, v);
  return out;
}

struct MultigridPreconditioner::Impl {
  std::vector<Level> levels;
  std::vector<int> row_dof;  ///< free row → DOF of level 0 (3 v + axis)
  bool have_structure = false;
  std::uint64_t pattern = 0;  ///< pattern_hash of the A the structure was built for
  std::vector<int> value_slot;  ///< per stored entry of A, its index in level 0's A.val (values() copies by it)
  // The coarsest level as a scalar matrix for the direct solver.
  std::vector<int> coarse_dof;    ///< its free DOFs (3 node + axis)
  std::vector<int> coarse_value;  ///< per stored entry of `coarse`, its index in the last level's A.val
  SparseLower coarse;
  std::unique_ptr<LinearSolver> direct = make_ldlt_solver();  // small: no BLAS (its buffers and threads) needed
  Eigen::VectorXd coarse_b;
  std::vector<double> row;  ///< work: one block row of A T (smooth_prolongator(): 9 per coarse node)

  Coarsening coarsening;

  Impl(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how);
  void grow(const std::function<void()>& coarsen);
  void coarsen();
  void aggregate();
  void coarse_pattern(std::size_t l);
  void structure(const SparseLower& A);
  bool values(const SparseLower& A, double shift, bool refresh);
  bool coarse_current = false;  ///< the coarse levels were made from a matrix of the current structure
  bool prepare_smoother(Level& L);
  void smooth_prolongator(std::size_t l);
  void galerkin(Level& fine, Level& coarse_level);
  void vcycle(std::size_t l);
  void product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap);
  Eigen::VectorXd product_in, product_out;
  /// A level of fewer nodes runs on one thread (a parallel region costs more than it saves) and smooths by
  /// lexicographic Gauss–Seidel (x read in node order); larger ones by the multi-colour sweep in parallel.
  /// Chosen by size when the structure is made (Level::lexicographic), never by the thread count, so results
  /// stay the same for any thread count.
  int parallel_nodes = 16384;
  [[nodiscard]] bool parallel(const Level& L) const { return L.nodes >= parallel_nodes; }
  /// The sweeps: also at least parallel_nodes / 8 nodes per colour on average (a barrier after each colour).
  [[nodiscard]] bool parallel_sweep(const Level& L) const {
    return parallel(L) && L.nodes >= parallel_nodes / 8 * (static_cast<int>(L.colour_start.size()) - 1);
  }
};

namespace {

/// The smoother's colours and block rows of L (see Level), from its pattern. Lattice levels: the parity of the
/// node's lattice coordinates (8 colours), used where it is valid — no block couples two nodes of one parity,
/// as on 27-point stencils, which trilinear Galerkin products keep — else, and for aggregation levels, greedy
/// colouring in node order (each node the smallest colour none of its lower neighbours has). A lexicographic
/// level's rows are sorted by node instead.
void sweep_rows(Level& L, bool lexicographic) {
  L.lexicographic = lexicographic;
  const int n = L.nodes;
  L.row_start.assign(n + 1, 0);
  for (int i = 0; i < n; ++i)
    for (int s = L.A.start[i]; s + 1 < L.A.start[i + 1]; ++s) ++L.row_start[i + 1], ++L.row_start[L.A.col[s] + 1];
  for (int i = 0; i < n; ++i) L.row_start[i + 1] += L.row_start[i];
  L.row_node.resize(L.row_start[n]);
  L.row_slot.resize(L.row_start[n]);
  {
    std::vector<int> next(L.row_start.begin(), L.row_start.end() - 1);
    for (int i = 0; i < n; ++i)
      for (int s = L.A.start[i]; s + 1 < L.A.start[i + 1]; ++s) {
        const int k = L.A.col[s];
        L.row_node[next[i]] = k, L.row_slot[next[i]++] = s;
        L.row_node[next[k]] = i, L.row_slot[next[k]++] = s;
      }
  }
  L.colour.assign(n, 0);
  bool valid = !L.at.empty();
  for (int i = 0; i < n && valid; ++i) {
    const Eigen::Vector3i& a = L.at[i];
    L.colour[i] = (a.x() & 1) | (a.y() & 1) << 1 | (a.z() & 1) << 2;
  }
  for (int i = 0; i < n && valid; ++i)
    for (int s = L.A.start[i]; s + 1 < L.A.start[i + 1] && valid; ++s) valid = L.colour[L.A.col[s]] != L.colour[i];
  if (!valid) {
    std::vector<int> seen;  // seen[c] == i + 1: colour c is taken by a neighbour of i
    for (int i = 0; i < n; ++i) {
      for (int s = L.A.start[i]; s + 1 < L.A.start[i + 1]; ++s) {
        const int c = L.colour[L.A.col[s]];
        if (c >= static_cast<int>(seen.size())) seen.resize(c + 1, 0);
        seen[c] = i + 1;
      }
      int c = 0;
      while (c < static_cast<int>(seen.size()) && seen[c] == i + 1) ++c;
      L.colour[i] = c;
    }
  }
  const int colours = n ? *std::max_element(L.colour.begin(), L.colour.end()) + 1 : 0;
  L.colour_start.assign(colours + 1, 0);
  for (int i = 0; i < n; ++i) ++L.colour_start[L.colour[i] + 1];
  for (int c = 0; c < colours; ++c) L.colour_start[c + 1] += L.colour_start[c];
  L.by_colour.resize(n);
  {
    std::vector<int> next(L.colour_start.begin(), L.colour_start.end() - 1);
    for (int i = 0; i < n; ++i) L.by_colour[next[L.colour[i]]++] = i;
  }
  // The rows in sweep order: each sweep then reads them front to back (by node, a colour's rows lie every
  // eighth row apart: bench_multigrid's hex V-cycle took 0.84 and 0.89 of that time on 1 and 2 threads,
  // medians of 10 pairs of runs in turn).
  std::vector<int> start(n), slot(L.row_slot.size()), node(L.row_node.size());
  L.row_end.resize(n);
  int filled = 0;
  for (int q = 0; q < n; ++q) {
    const int i = lexicographic ? q : L.by_colour[q];
    start[i] = filled;
    for (int e = L.row_start[i]; e < L.row_start[i + 1]; ++e, ++filled) slot[filled] = L.row_slot[e], node[filled] = L.row_node[e];
    L.row_end[i] = filled;
  }
  L.row_start = std::move(start);
  L.row_slot = std::move(slot);
  L.row_node = std::move(node);
  L.before.assign(n, 0);
  std::vector<std::pair<std::int64_t, int>> entries;
  for (int i = 0; i < n; ++i) {
    entries.clear();
    for (int e = L.row_start[i]; e < L.row_end[i]; ++e)
      entries.emplace_back(static_cast<std::int64_t>(lexicographic ? 0 : L.colour[L.row_node[e]]) * n + L.row_node[e], L.row_slot[e]);
    std::sort(entries.begin(), entries.end());
    for (std::size_t q = 0; q < entries.size(); ++q) {
      const int e = L.row_start[i] + static_cast<int>(q), k = static_cast<int>(entries[q].first % n);
      L.row_node[e] = k;
      L.row_slot[e] = entries[q].second;
      if (lexicographic ? k < i : L.colour[k] < L.colour[i]) ++L.before[i];
    }
  }
}

/// The product's chunks of L (see Level): 16 at most, of at least 2048 nodes each.
void product_chunks(Level& L) {
  const int n = L.nodes, chunks = std::clamp(n / 2048, 1, 16);
  L.chunk_start.resize(chunks + 1);
  L.chunk_low.resize(chunks);
  L.chunk_offset.assign(chunks + 1, 0);
  for (int c = 0; c <= chunks; ++c) L.chunk_start[c] = static_cast<int>(static_cast<std::int64_t>(n) * c / chunks);
  for (int c = 0; c < chunks; ++c) {
    int low = L.chunk_start[c];
    for (int i = L.chunk_start[c]; i < L.chunk_start[c + 1]; ++i) low = std::min(low, L.A.col[L.A.start[i]]);
    L.chunk_low[c] = low;
    L.chunk_offset[c + 1] = L.chunk_offset[c] + 3 * static_cast<std::size_t>(L.chunk_start[c + 1] - low);
  }
  L.spill.resize(L.chunk_offset[chunks]);
}

/// Pᵀ's index: per coarse node, the entries of `down` that reach it, in fine-node order.
void transpose_transfer(Level& F, int coarse_nodes) {
  F.up_start.assign(coarse_nodes + 1, 0);
  for (int I : F.down.node) ++F.up_start[I + 1];
  for (int I = 0; I < coarse_nodes; ++I) F.up_start[I + 1] += F.up_start[I];
  F.up_entry.resize(F.down.node.size());
  F.up_fine.resize(F.down.node.size());
  std::vector<int> next(F.up_start.begin(), F.up_start.end() - 1);
  for (int i = 0; i < F.nodes; ++i)
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
      F.up_fine[next[F.down.node[p]]] = i;
      F.up_entry[next[F.down.node[p]]++] = p;
    }
}

}  // namespace

MultigridPreconditioner::Impl::Impl(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how)
    : coarsening(how) {
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
  if (how == Coarsening::aggregation) {
    // The rigid-body modes at rest: translations, and rotations about the centroid (for conditioning).
    const Eigen::Vector3d centre = L.nodes ? Eigen::Vector3d(mesh.vertices.rowwise().mean()) : Eigen::Vector3d::Zero();
    L.near_null.assign(18 * static_cast<std::size_t>(L.nodes), 0.0);
    for (int v = 0; v < L.nodes; ++v) {
      const Eigen::Vector3d p = mesh.vertices.col(v) - centre;
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> b(&L.near_null[18 * static_cast<std::size_t>(v)]);
      b.leftCols<3>().setIdentity();
      b.rightCols<3>() << 0.0, p.z(), -p.y(), -p.z(), 0.0, p.x(), p.y(), -p.x(), 0.0;  // columns e_a × p
    }
    levels.push_back(std::move(L));
    return;  // the levels follow the matrix's pattern (structure())
  }
  const LatticeCoordinates lattice = lattice_coordinates(mesh);
  L.at.resize(L.nodes);
  L.piece = lattice.piece;
  for (int v = 0; v < L.nodes; ++v) L.at[v] = lattice.coordinates.col(v);
  L.cells.resize(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int k = 0; k < 8; ++k) L.cells[c][k] = mesh.cells(k, c);
  levels.push_back(std::move(L));
  grow([this] { coarsen(); });
}

/// Appends levels, each by `coarsen`, until the last has at most kCoarsestUnknowns (aggregation:
/// kCoarsestAggregationUnknowns) free DOFs; a level that keeps more than kMinReduction of the one before (or
/// none) is dropped and ends the hierarchy.
void MultigridPreconditioner::Impl::grow(const std::function<void()>& coarsen) {
  const Eigen::Index coarsest = coarsening == Coarsening::lattice ? kCoarsestUnknowns : kCoarsestAggregationUnknowns;
  while (levels.size() < kMaxLevels && levels.back().unknowns() > coarsest) {
    const Eigen::Index before = levels.back().unknowns();
    coarsen();
    if (levels.back().unknowns() > kMinReduction * static_cast<double>(before) || levels.back().unknowns() == 0) {
      levels.pop_back();
      levels.back().down = Transfer{};
      break;
    }
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
        const double block[9] = {w, 0.0, 0.0, 0.0, w, 0.0, 0.0, 0.0, w};
        F.down.push(parent, block);
        F.down.weight.push_back(w);
        if (w == 1.0) coincident[parent] = v;
      }
    }
    F.down.start.push_back(static_cast<int>(F.down.node.size()));
  }
  // A coarse DOF is free where it reaches a free fine DOF and the fine vertex at its place (if any) is free there.
  std::vector<std::uint8_t> reaches(3 * static_cast<std::size_t>(C.nodes), 0);
  for (int v = 0; v < F.nodes; ++v)
    for (int p = F.down.start[v]; p < F.down.start[v + 1]; ++p)
      for (int a = 0; a < 3; ++a) reaches[3 * F.down.node[p] + a] |= F.free[3 * v + a];
  C.free.assign(3 * static_cast<std::size_t>(C.nodes), 0);
  for (int n = 0; n < C.nodes; ++n)
    for (int a = 0; a < 3; ++a) C.free[3 * n + a] = reaches[3 * n + a] && (coincident[n] < 0 || F.free[3 * coincident[n] + a]);
  levels.push_back(std::move(C));
}

/// Level l + 1's block pattern, Pᵀ A P's, from level l's and P's.
void MultigridPreconditioner::Impl::coarse_pattern(std::size_t l) {
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

/// Smoothed aggregation: appends the level of the aggregates of the last level's nodes, from its block
/// pattern (every connection counts as strong), with the tentative prolongator from the rigid-body modes
/// and the smoothed prolongator's pattern (values: smooth_prolongator()).
void MultigridPreconditioner::Impl::aggregate() {
  Level& F = levels.back();
  const int n = F.nodes;
  // Every block of each row: (i, k < i) stored in row i, the diagonal, then (k > i, i)ᵀ stored in row k.
  F.full_start.assign(n + 1, 0);
  for (int i = 0; i < n; ++i)
    for (int s = F.A.start[i]; s < F.A.start[i + 1]; ++s) {
      ++F.full_start[i + 1];
      if (F.A.col[s] != i) ++F.full_start[F.A.col[s] + 1];
    }
  for (int i = 0; i < n; ++i) F.full_start[i + 1] += F.full_start[i];
  F.full_node.resize(F.full_start[n]);
  F.full_slot.resize(F.full_start[n]);
  {
    std::vector<int> next(F.full_start.begin(), F.full_start.end() - 1);
    for (int i = 0; i < n; ++i)  // row i's own blocks first (columns ≤ i), as rows below i are reached later
      for (int s = F.A.start[i]; s < F.A.start[i + 1]; ++s) {
        const int k = F.A.col[s];
        F.full_node[next[i]] = k;
        F.full_slot[next[i]++] = s;
        if (k != i) {
          F.full_node[next[k]] = i;
          F.full_slot[next[k]++] = s;
        }
      }
  }
  // Greedy aggregation of the nodes with a free DOF, in node order: (1) a node whose neighbours are all
  // unaggregated starts an aggregate with them; (2) a node left over joins the first aggregate of step 1
  // among its neighbours; (3) one with none (isolated) starts its own with its unaggregated neighbours.
  F.aggregate.assign(n, -1);
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (!F.has_free(i) || F.aggregate[i] >= 0) continue;
    bool alone = true;
    for (int p = F.full_start[i]; p < F.full_start[i + 1] && alone; ++p)
      alone = F.aggregate[F.full_node[p]] < 0;
    if (!alone) continue;
    for (int p = F.full_start[i]; p < F.full_start[i + 1]; ++p)
      if (F.has_free(F.full_node[p])) F.aggregate[F.full_node[p]] = count;
    F.aggregate[i] = count++;
  }
  const std::vector<int> first = F.aggregate;
  for (int i = 0; i < n; ++i) {
    if (!F.has_free(i) || F.aggregate[i] >= 0) continue;
    for (int p = F.full_start[i]; p < F.full_start[i + 1] && F.aggregate[i] < 0; ++p) F.aggregate[i] = first[F.full_node[p]];
    if (F.aggregate[i] >= 0) continue;
    for (int p = F.full_start[i]; p < F.full_start[i + 1]; ++p)
      if (F.has_free(F.full_node[p]) && F.aggregate[F.full_node[p]] < 0) F.aggregate[F.full_node[p]] = count;
    F.aggregate[i] = count++;
  }
  // Tentative prolongator: per aggregate, an orthonormal basis Q of its rows of the near-null space B (the
  // rows of DOFs that are not free zeroed; QR with column pivoting keeps its rank r ≤ 6); the coarse near-null
  // space is Qᵀ B, so that P B_coarse = B. Each aggregate is two coarse nodes (DOFs 0–2 and 3–5), its DOFs
  // from r on not free.
  std::vector<std::vector<int>> members(count);
  for (int i = 0; i < n; ++i)
    if (F.aggregate[i] >= 0) members[F.aggregate[i]].push_back(i);
  Level C;
  C.nodes = 2 * count;
  C.free.assign(6 * static_cast<std::size_t>(count), 0);
  C.near_null.assign(36 * static_cast<std::size_t>(count), 0.0);
  F.tentative.assign(18 * static_cast<std::size_t>(n), 0.0);
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, 6>;
  for (int a = 0; a < count; ++a) {
    const auto& m = members[a];
    Rows B(3 * static_cast<Eigen::Index>(m.size()), 6);
    for (std::size_t k = 0; k < m.size(); ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 6; ++c)
          B(3 * static_cast<Eigen::Index>(k) + r, c) = F.free[3 * m[k] + r] ? F.near_null[18 * static_cast<std::size_t>(m[k]) + 6 * r + c] : 0.0;
    Eigen::ColPivHouseholderQR<Rows> qr(B);
    qr.setThreshold(1e-10);
    const Eigen::Index rank = std::min<Eigen::Index>(qr.rank(), 6);
    const Rows Q = qr.householderQ() * Eigen::MatrixXd::Identity(B.rows(), 6);
    Eigen::Matrix<double, 6, 6> coarse = Eigen::Matrix<double, 6, 6>::Zero();
    coarse.topRows(rank) = Q.leftCols(rank).transpose() * B;
    for (std::size_t k = 0; k < m.size(); ++k)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < rank; ++c) F.tentative[18 * static_cast<std::size_t>(m[k]) + 6 * r + c] = Q(3 * static_cast<Eigen::Index>(k) + r, c);
    for (int d = 0; d < 6; ++d) {
      C.free[6 * static_cast<std::size_t>(a) + d] = d < rank;
      for (int c = 0; c < 6; ++c) C.near_null[36 * static_cast<std::size_t>(a) + 6 * d + c] = coarse(d, c);
    }
  }
  // The smoothed prolongator (I − ω D⁻¹ A) P_tent reaches, from node i, the aggregates of i and its neighbours.
  F.down = Transfer{};
  std::vector<int> parents;
  for (int i = 0; i < n; ++i) {
    parents.clear();
    if (F.has_free(i))
      for (int p = F.full_start[i]; p < F.full_start[i + 1]; ++p)
        if (const int g = F.aggregate[F.full_node[p]]; g >= 0) parents.insert(parents.end(), {2 * g, 2 * g + 1});
    sort_unique(parents);
    const double zero[9] = {};
    for (int I : parents) F.down.push(I, zero);
    F.down.start.push_back(static_cast<int>(F.down.node.size()));
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
  {
    // Where each stored entry of A goes. Column c (DOF b of node j) holds entries (i a, j b), i ≥ j: block
    // (i, j)'s entry (a, b). Columns come in increasing j, so each row's cursor only moves forward to (i, j).
    std::vector<int> cursor(L0.A.start.begin(), L0.A.start.end() - 1);
    value_slot.resize(static_cast<std::size_t>(A.nonZeros()));
    for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
      const int dc = row_dof[c], j = dc / 3, b = dc % 3;
      for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k) {
        const int dr = row_dof[A.innerIndexPtr()[k]], i = dr / 3;
        while (L0.A.col[cursor[i]] < j) ++cursor[i];  // stops at the diagonal block (i ≥ j) at the latest
        if (L0.A.col[cursor[i]] != j) throw std::logic_error("multigrid: the matrix's pattern does not hold its own entries");
        value_slot[static_cast<std::size_t>(k)] = 9 * cursor[i] + 3 * (dr % 3) + b;
      }
    }
  }
  if (coarsening == Coarsening::lattice) {
    for (std::size_t l = 0; l + 1 < levels.size(); ++l) coarse_pattern(l);
  } else {
    levels.resize(1);
    levels.front().down = Transfer{};
    grow([this] {
      aggregate();
      coarse_pattern(levels.size() - 2);
    });
  }
  for (Level& l : levels) {
    l.diagonal.resize(l.nodes);
    for (int i = 0; i < l.nodes; ++i) l.diagonal[i] = l.A.find(i, i);
    l.inverse.assign(9 * static_cast<std::size_t>(l.nodes), 0.0);
    l.x.resize(3 * l.nodes);
    l.b.resize(3 * l.nodes);
    l.r.resize(3 * l.nodes);
    sweep_rows(l, !parallel(l));
    product_chunks(l);
  }
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) transpose_transfer(levels[l], levels[l + 1].nodes);
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

namespace {

/// R += Wᵀ a for 3×3 row-major blocks; W diagonal (the lattice's transfers: trilinear weights times the
/// identity, masked to the free DOFs) needs a third of the products.
template <bool kDiagonal>
inline void add_transposed_product(const double* w, const double* a, bool transpose_a, double* R) {
  const auto at = [&](int r, int c) { return transpose_a ? a[3 * c + r] : a[3 * r + c]; };
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      if constexpr (kDiagonal) R[3 * r + c] += w[4 * r] * at(r, c);
      else R[3 * r + c] += w[r] * at(0, c) + w[3 + r] * at(1, c) + w[6 + r] * at(2, c);
    }
}

/// Y += r W for 3×3 row-major blocks (W diagonal as above where kDiagonal).
template <bool kDiagonal>
inline void add_product(const double* r, const double* w, double* Y) {
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) {
      if constexpr (kDiagonal) Y[3 * i + c] += r[3 * i + c] * w[4 * c];
      else Y[3 * i + c] += r[3 * i] * w[c] + r[3 * i + 1] * w[3 + c] + r[3 * i + 2] * w[6 + c];
    }
}

/// The next level's A from this one's, Pᵀ A P, one coarse block row I at a time, rows in parallel: first
/// R_k = Σ_i P_iIᵀ A_ik over I's fine nodes i and every block of their rows (both triangles), then
/// C_IK = Σ_k R_k P_kK for the coarse K ≤ I (the diagonal block made symmetric); then the coarse DOFs that are
/// not free masked out. Each row's sums run in an order fixed by the structure alone, so the result does not
/// depend on the thread count. (Figure 1's finest product: 40 ms by the serial scatter of fine rows that this
/// replaced, 42 ms here on one thread, 24 ms on two.)
template <bool kDiagonal>
void galerkin_rows(const Level& F, Level& C, bool in_parallel) {
  int outside = 0;  // coarse blocks reached outside C's pattern (none: the structure made it from the same P)
#pragma omp parallel if (in_parallel) reduction(+ : outside)
  {
    std::vector<double> R(9 * static_cast<std::size_t>(F.nodes), 0.0), Y(9 * static_cast<std::size_t>(C.nodes), 0.0);
    std::vector<int> reached, reached_coarse;
    std::vector<char> seen(F.nodes, 0), seen_coarse(C.nodes, 0);
    const double* val = F.A.val.data();
#pragma omp for schedule(dynamic, 64)
    for (int I = 0; I < C.nodes; ++I) {
      for (int q = F.up_start[I]; q < F.up_start[I + 1]; ++q) {
        const int i = F.up_fine[q];
        const double* w = &F.down.block[9 * static_cast<std::size_t>(F.up_entry[q])];
        const auto add = [&](int k, std::size_t slot, bool transpose) {
          if (!seen[k]) {
            seen[k] = 1;
            reached.push_back(k);
          }
          add_transposed_product<kDiagonal>(w, val + 9 * slot, transpose, &R[9 * static_cast<std::size_t>(k)]);
        };
        add(i, F.diagonal[i], false);
        for (int e = F.row_start[i]; e < F.row_end[i]; ++e) add(F.row_node[e], F.row_slot[e], F.row_node[e] > i);
      }
      for (int k : reached) {
        const double* r = &R[9 * static_cast<std::size_t>(k)];
        for (int p = F.down.start[k]; p < F.down.start[k + 1]; ++p) {
          const int K = F.down.node[p];
          if (K > I) continue;
          if (!seen_coarse[K]) {
            seen_coarse[K] = 1;
            reached_coarse.push_back(K);
          }
          add_product<kDiagonal>(r, &F.down.block[9 * static_cast<std::size_t>(p)], &Y[9 * static_cast<std::size_t>(K)]);
        }
        std::fill_n(&R[9 * static_cast<std::size_t>(k)], 9, 0.0);
        seen[k] = 0;
      }
      reached.clear();
      // Row I of C: every stored block is written (zero where nothing reached it), its DOFs that are not free
      // masked out.
      for (int s = C.A.start[I]; s < C.A.start[I + 1]; ++s) {
        const int K = C.A.col[s];
        Block3 c(&C.A.val[9 * static_cast<std::size_t>(s)]);
        if (seen_coarse[K]) {
          const ConstBlock3 y(&Y[9 * static_cast<std::size_t>(K)]);
          if (K < I) c = y;
          else c = 0.5 * (y + y.transpose());
          std::fill_n(&Y[9 * static_cast<std::size_t>(K)], 9, 0.0);
          seen_coarse[K] = 0;
        } else {
          c.setZero();
        }
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            if (!C.free[3 * I + a] || !C.free[3 * K + b]) c(a, b) = 0.0;
      }
      for (int K : reached_coarse)
        if (seen_coarse[K]) {
          ++outside;
          std::fill_n(&Y[9 * static_cast<std::size_t>(K)], 9, 0.0);
          seen_coarse[K] = 0;
        }
      reached_coarse.clear();
    }
  }
  if (outside > 0) throw std::logic_error("multigrid: Galerkin product reached blocks outside the coarse pattern");
}

}  // namespace

void MultigridPreconditioner::Impl::galerkin(Level& F, Level& C) {
  // The lattice's transfers are diagonal blocks (tests/solve/test_multigrid.cpp checks the products against
  // the explicit Pᵀ A P); smoothed aggregation's are full.
  if (coarsening == Coarsening::lattice) galerkin_rows<true>(F, C, parallel(F));
  else galerkin_rows<false>(F, C, parallel(F));
}

/// The smoother's values for L's A: the rows' blocks in row order (read in a stream, each block as A_ik), and
/// the inverses of the diagonal blocks' free parts (Cholesky: false where a block is not positive definite,
/// which proves that A is not).
bool MultigridPreconditioner::Impl::prepare_smoother(Level& L) {
  L.row_val.resize(9 * L.row_slot.size() + 3);
  std::fill(L.row_val.end() - 3, L.row_val.end(), 0.0f);
#pragma omp parallel for schedule(static) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i)
    for (int e = L.row_start[i]; e < L.row_end[i]; ++e) {
      const ConstBlock3 a(&L.A.val[9 * static_cast<std::size_t>(L.row_slot[e])]);
      Eigen::Map<Eigen::Matrix<float, 3, 3, Eigen::ColMajor>> to(&L.row_val[9 * static_cast<std::size_t>(e)]);
      if (L.row_node[e] < i) to = a.cast<float>();
      else to = a.transpose().cast<float>();
    }
  int failed = 0;  // nodes whose block is not positive definite (each node's inverse is its own: any order)
#pragma omp parallel for schedule(static) reduction(+ : failed) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i) {
    Eigen::Matrix3d D = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&L.A.val[9 * static_cast<std::size_t>(L.diagonal[i])]);
    for (int a = 0; a < 3; ++a)
      if (!L.free[3 * i + a]) D(a, a) = 1.0;
    const Eigen::LLT<Eigen::Matrix3d> llt(D);
    if (llt.info() != Eigen::Success || !(llt.matrixLLT().diagonal().array() > 0.0).all()) {
      ++failed;
      continue;
    }
    Eigen::Matrix3d inv = llt.solve(Eigen::Matrix3d::Identity());
    for (int a = 0; a < 3; ++a)
      if (!L.free[3 * i + a]) inv.row(a).setZero(), inv.col(a).setZero();
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(&L.inverse[9 * static_cast<std::size_t>(i)]) = inv;
  }
  return failed == 0;
}

bool MultigridPreconditioner::Impl::values(const SparseLower& A, double shift, bool refresh) {
  Level& L0 = levels.front();
  // A's entries into their blocks (each to its own slot: in parallel; compute() rebuilt the structure, and
  // with it value_slot, for a new pattern). Figure 1: 14 ms per set-up by the serial walk with a cursor per
  // row that this replaces, 5 ms by the map.
  if (value_slot.size() != static_cast<std::size_t>(A.nonZeros())) throw std::logic_error("multigrid: the matrix's pattern changed unnoticed");
  const double* v = A.valuePtr();
  double* to = L0.A.val.data();
  const int* slot = value_slot.data();
  const Eigen::Index entries = A.nonZeros();
#pragma omp parallel for schedule(static) if (parallel(L0))
  for (Eigen::Index k = 0; k < entries; ++k) to[slot[k]] = v[k];
  // The upper halves of the diagonal blocks by symmetry, and the shift.
#pragma omp parallel for schedule(static) if (parallel(L0))
  for (int i = 0; i < L0.nodes; ++i) {
    double* d = &L0.A.val[9 * static_cast<std::size_t>(L0.diagonal[i])];
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b) d[3 * a + b] = d[3 * b + a];
    for (int a = 0; a < 3; ++a)
      if (L0.free[3 * i + a]) d[4 * a] += shift;
  }
  if (!refresh && coarse_current && levels.size() > 1) return prepare_smoother(L0);
  coarse_current = false;
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) {
    if (!prepare_smoother(levels[l])) return false;
    if (coarsening == Coarsening::aggregation) smooth_prolongator(l);
    galerkin(levels[l], levels[l + 1]);
  }
  const Level& K = levels.back();
  for (std::size_t e = 0; e < coarse_value.size(); ++e) coarse.valuePtr()[e] = K.A.val[coarse_value[e]];
  coarse_current = coarse.rows() == 0 || direct->try_factorize(coarse);
  return coarse_current;
}

namespace {

/// y −= a x for a row-major 3×3 block a; yt −= aᵀ x.
template <class T>
inline void subtract(const T* a, const double* x, double* y) {
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

/// Four doubles (GCC's and Clang's vector extensions; AVX on x86): a 3-vector in lanes 0–2, lane 3 unused.
using Lanes = double __attribute__((vector_size(32)));
using FloatLanes = float __attribute__((vector_size(16)));

/// The four floats from p on, as doubles.
inline Lanes widen4(const float* p) {
#ifdef __AVX__
  return Lanes(_mm256_cvtps_pd(_mm_loadu_ps(p)));  // GCC splits the generic form's load into halves
#else
  FloatLanes f;
  std::memcpy(&f, p, sizeof f);
  return __builtin_convertvector(f, Lanes);
#endif
}

inline Lanes lanes3(const double* p) { return Lanes{p[0], p[1], p[2], 0.0}; }
inline void store3(const Lanes& v, double* p) { p[0] = v[0], p[1] = v[1], p[2] = v[2]; }

/// t += a x lane by lane, one rounding (a fused multiply-add where the CPU has one).
inline Lanes multiply_add(const Lanes& a, double x, const Lanes& t) {
#ifdef __FMA__
  return Lanes(_mm256_fmadd_pd(__m256d(a), _mm256_set1_pd(x), __m256d(t)));
#else
  return t + a * x;
#endif
}

/// s −= Σ A_ik x_k over row i's off-diagonal blocks `from` .. `to` (sweep_rows()), single-precision blocks
/// stored by columns: column j of a block, widened to four doubles (the fourth is the float after it; it goes
/// to the sums' unused lane), times x_kj. Six independent sums (the columns of the even and of the odd blocks)
/// with fused multiply-adds: the loop is not one chain of dependent additions (bench_multigrid, hex V-cycle:
/// 0.93-0.97 of the time of one sum by unfused operations).
inline void subtract_row(const Level& L, int from, int to, const double* x, Lanes& s) {
  const float* val = L.row_val.data() + 9 * static_cast<std::size_t>(from);
  const int* node = L.row_node.data();
  Lanes t0{}, t1{}, t2{}, u0{}, u1{}, u2{};
  int e = from;
  for (; e + 1 < to; e += 2, val += 18) {
    const double* xa = x + 3 * node[e];
    const double* xb = x + 3 * node[e + 1];
    t0 = multiply_add(widen4(val), xa[0], t0);
    t1 = multiply_add(widen4(val + 3), xa[1], t1);
    t2 = multiply_add(widen4(val + 6), xa[2], t2);
    u0 = multiply_add(widen4(val + 9), xb[0], u0);
    u1 = multiply_add(widen4(val + 12), xb[1], u1);
    u2 = multiply_add(widen4(val + 15), xb[2], u2);
  }
  if (e < to) {
    const double* xa = x + 3 * node[e];
    t0 = multiply_add(widen4(val), xa[0], t0);
    t1 = multiply_add(widen4(val + 3), xa[1], t1);
    t2 = multiply_add(widen4(val + 6), xa[2], t2);
  }
  s -= ((t0 + u0) + (t1 + u1)) + (t2 + u2);
}

/// x_i = D_i⁻¹ (b_i − Σ A_ik x_k) over all blocks of row i (whole = true) or its first `before` (the others
/// meet x = 0).
inline void relax_node(Level& L, int i, bool whole) {
  Lanes s = lanes3(L.b.data() + 3 * i);
  subtract_row(L, L.row_start[i], whole ? L.row_end[i] : L.row_start[i] + L.before[i], L.x.data(), s);
  const double t[3] = {s[0], s[1], s[2]};
  solve_diagonal(L, i, t, L.x.data() + 3 * i);
}

/// relax_node() for the nodes of colour c. Nodes of one colour are not coupled: they update in parallel,
/// each row's sum in its fixed order, so the result does not depend on the thread count.
void relax_colour(Level& L, int c, bool whole) {
  const int first = L.colour_start[c], last = L.colour_start[c + 1];
#pragma omp for schedule(static)
  for (int q = first; q < last; ++q) relax_node(L, L.by_colour[q], whole);
}

/// A forward lexicographic nodal-block Gauss–Seidel sweep for L.A x = L.b from x = 0 (the blocks of higher
/// nodes meet only zeros): the smoother of a lexicographic level.
void forward_sweep_in_order(Level& L) {
  L.x.setZero();
  for (int i = 0; i < L.nodes; ++i) relax_node(L, i, false);
}

/// The backward lexicographic sweep on L.x, nodes in descending order, whole rows.
void backward_sweep_in_order(Level& L) {
  for (int i = L.nodes - 1; i >= 0; --i) relax_node(L, i, true);
}

/// A forward multi-colour nodal-block Gauss–Seidel sweep for L.A x = L.b from x = 0, colour by colour.
void forward_sweep(Level& L, bool parallel) {
  L.x.setZero();
  const int colours = static_cast<int>(L.colour_start.size()) - 1;
#pragma omp parallel if (parallel)
  for (int c = 0; c < colours; ++c) relax_colour(L, c, false);
}

/// The backward sweep on L.x: the colours in reverse order (the forward sweep's adjoint, so that the
/// V-cycle is symmetric).
void backward_sweep(Level& L, bool parallel) {
  const int colours = static_cast<int>(L.colour_start.size()) - 1;
#pragma omp parallel if (parallel)
  for (int c = colours - 1; c >= 0; --c) relax_colour(L, c, true);
}

/// L.r = L.b − Ã L.x right after forward_sweep() (or forward_sweep_in_order()), row by row in parallel, Ã the
/// smoother's matrix (single-precision off-diagonal blocks: the sweeps' residuals are Ã's, so this one must be
/// too for the V-cycle to stay symmetric). The sweep made row i's equation hold with the lower colours' (nodes')
/// final x and the higher ones' zeros, so only the blocks of higher colours (nodes) are left: r_i = −Σ A_ik x_k
/// over them (equal in exact arithmetic, half the blocks).
void forward_residual(Level& L, bool parallel) {
  const double* x = L.x.data();
#pragma omp parallel for schedule(static) if (parallel)
  for (int q = 0; q < L.nodes; ++q) {  // in sweep order, as the rows lie
    const int i = L.lexicographic ? q : L.by_colour[q];
    Lanes s{0.0, 0.0, 0.0, 0.0};
    subtract_row(L, L.row_start[i] + L.before[i], L.row_end[i], x, s);
    store3(s, L.r.data() + 3 * i);
  }
}

/// Four doubles from p on.
inline Lanes lanes4(const double* p) {
#ifdef __AVX__
  return Lanes(_mm256_loadu_pd(p));
#else
  Lanes v;
  std::memcpy(&v, p, sizeof v);
  return v;
#endif
}

/// y = −A x from A's lower block triangle, by L's chunks in parallel: each
/// chunk's rows in order, then each row's sum and the chunks' spills into it in chunk order (a fixed order:
/// the result does not depend on the thread count). Four lanes at a time: a block's rows r_k (4 doubles from
/// each, the fourth the next row's first: it meets x's zero lane, or goes to the spill's unused one) give
/// row i's sums lane by lane, t_k += r_k ∘ x_j, added across the lanes at the row's end, and the spill
/// −= Σ_k r_k x_ik.
void subtract_product(Level& L, const double* x, double* y, bool parallel) {
  const double* val = L.A.val.data();
  const int chunks = static_cast<int>(L.chunk_low.size());
#pragma omp parallel if (parallel)
  {
#pragma omp for schedule(static)
    for (int c = 0; c < chunks; ++c) {
      double* spill = L.spill.data() + L.chunk_offset[c];
      const int low = L.chunk_low[c];
      std::fill(spill, L.spill.data() + L.chunk_offset[c + 1], 0.0);
      for (int i = L.chunk_start[c]; i < L.chunk_start[c + 1]; ++i) {
        const Lanes xi = lanes3(x + 3 * i);
        Lanes t0{}, t1{}, t2{};
        const int end = L.A.start[i + 1] - 1;  // the diagonal block
        for (int k = L.A.start[i]; k < end; ++k) {
          const double* a = val + 9 * static_cast<std::size_t>(k);
          const Lanes r0 = lanes4(a), r1 = lanes4(a + 3), r2 = lanes4(a + 6), xj = lanes3(x + 3 * L.A.col[k]);
          t0 += r0 * xj, t1 += r1 * xj, t2 += r2 * xj;
          double* to = spill + 3 * (L.A.col[k] - low);
          store3(lanes3(to) - (r0 * xi[0] + r1 * xi[1] + r2 * xi[2]), to);
        }
        const double* d = val + 9 * static_cast<std::size_t>(end);
        t0 += lanes4(d) * xi, t1 += lanes4(d + 3) * xi, t2 += lanes4(d + 6) * xi;
        const Lanes* t[3] = {&t0, &t1, &t2};
        for (int a = 0; a < 3; ++a) y[3 * i + a] = 0.0 - (((*t[a])[0] + (*t[a])[1]) + (*t[a])[2]);
      }
    }
#pragma omp for schedule(static)
    for (int i = 0; i < L.nodes; ++i)
      for (int c = 0; c < chunks; ++c)
        if (L.chunk_low[c] <= i && i < L.chunk_start[c + 1]) {
          const double* spill = L.spill.data() + L.chunk_offset[c] + 3 * (i - L.chunk_low[c]);
          for (int a = 0; a < 3; ++a) y[3 * i + a] += spill[a];
        }
  }
}

}  // namespace

/// Smoothed aggregation's prolongator for the current A: P = (I − ω D⁻¹ A) P_tent, D the diagonal blocks,
/// ω = 4 / (3 ρ(D⁻¹ A)) with ρ from power iterations (5 % added): 15 from a fixed start vector for the
/// first matrix, then 5 from the last matrix's vector (consecutive Newton matrices differ little).
void MultigridPreconditioner::Impl::smooth_prolongator(std::size_t l) {
  Level& F = levels[l];
  Eigen::VectorXd &v = F.power, &w = F.r;
  const bool warm = v.size() == 3 * F.nodes;
  if (!warm) {
    v.resize(3 * F.nodes);
    for (int d = 0; d < 3 * F.nodes; ++d) v[d] = F.free[d] ? 1.0 + static_cast<double>((d * 7919) % 101) / 101.0 : 0.0;
  }
  double rho = 0.0;
  for (int it = 0; it < (warm ? 5 : 15); ++it) {
    const double norm = v.norm();
    if (!(norm > 0.0)) break;
    v /= norm;
    subtract_product(F, v.data(), w.data(), parallel(F));  // −A v
    for (int i = 0; i < F.nodes; ++i) solve_diagonal(F, i, w.data() + 3 * i, v.data() + 3 * i);
    rho = v.norm();
  }
  const double omega = rho > 0.0 ? 4.0 / (3.0 * 1.05 * rho) : 0.0;
  using Columns = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>, 0, Eigen::OuterStride<6>>;
  row.assign(9 * static_cast<std::size_t>(levels[l + 1].nodes), 0.0);
  for (int i = 0; i < F.nodes; ++i) {
    if (F.down.start[i] == F.down.start[i + 1]) continue;
    for (int p = F.full_start[i]; p < F.full_start[i + 1]; ++p) {
      const int k = F.full_node[p], g = F.aggregate[k];
      if (g < 0) continue;
      const ConstBlock3 stored(&F.A.val[9 * static_cast<std::size_t>(F.full_slot[p])]);
      const Eigen::Matrix3d a = k > i ? Eigen::Matrix3d(stored.transpose()) : Eigen::Matrix3d(stored);  // A_ik
      for (int c = 0; c < 2; ++c)
        Block3(&row[9 * static_cast<std::size_t>(2 * g + c)]).noalias() += a * Columns(&F.tentative[18 * static_cast<std::size_t>(k) + 3 * c]);
    }
    const ConstBlock3 inverse(&F.inverse[9 * static_cast<std::size_t>(i)]);
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
      const int I = F.down.node[p];
      Block3 P(&F.down.block[9 * static_cast<std::size_t>(p)]);
      Block3 t(&row[9 * static_cast<std::size_t>(I)]);
      P.noalias() = -omega * (inverse * t);
      if (I / 2 == F.aggregate[i]) P += Columns(&F.tentative[18 * static_cast<std::size_t>(i) + 3 * (I % 2)]);
      t.setZero();
    }
  }
}

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
  if (L.lexicographic) forward_sweep_in_order(L);
  else forward_sweep(L, parallel_sweep(L));
  forward_residual(L, parallel(L));
  // Restriction Pᵀ r on the coarse free DOFs (by coarse rows), prolongation P e on the fine ones.
#pragma omp parallel for schedule(static) if (parallel(C))
  for (int I = 0; I < C.nodes; ++I) {
    double e[3] = {0.0, 0.0, 0.0};
    if (L.down.weight.empty()) {
      for (int q = L.up_start[I]; q < L.up_start[I + 1]; ++q)
        subtract_transposed(&L.down.block[9 * static_cast<std::size_t>(L.up_entry[q])], L.r.data() + 3 * L.up_fine[q], e);
    } else {
      for (int q = L.up_start[I]; q < L.up_start[I + 1]; ++q) {
        const double w = L.down.weight[static_cast<std::size_t>(L.up_entry[q])], *r = L.r.data() + 3 * L.up_fine[q];
        for (int a = 0; a < 3; ++a) e[a] -= w * r[a];
      }
    }
    for (int a = 0; a < 3; ++a) C.b[3 * I + a] = C.free[3 * I + a] ? -e[a] : 0.0;
  }
  vcycle(l + 1);
#pragma omp parallel for schedule(static) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i) {
    double e[3] = {0.0, 0.0, 0.0};
    if (L.down.weight.empty()) {
      for (int p = L.down.start[i]; p < L.down.start[i + 1]; ++p)
        subtract(&L.down.block[9 * static_cast<std::size_t>(p)], C.x.data() + 3 * L.down.node[p], e);
    } else {
      for (int p = L.down.start[i]; p < L.down.start[i + 1]; ++p) {
        const double w = L.down.weight[static_cast<std::size_t>(p)], *x = C.x.data() + 3 * L.down.node[p];
        for (int a = 0; a < 3; ++a) e[a] -= w * x[a];
      }
    }
    for (int a = 0; a < 3; ++a)
      if (L.free[3 * i + a]) L.x[3 * i + a] -= e[a];
  }
  if (L.lexicographic) backward_sweep_in_order(L);
  else backward_sweep(L, parallel_sweep(L));
}

MultigridPreconditioner::MultigridPreconditioner(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how)
    : impl_(std::make_unique<Impl>(mesh, free_index, how)) {}

MultigridPreconditioner::~MultigridPreconditioner() = default;

bool MultigridPreconditioner::compute(const SparseLower& A, double shift, bool coarse) {
  if (A.rows() != static_cast<Eigen::Index>(impl_->row_dof.size()) || A.cols() != A.rows())
    throw std::invalid_argument(fmt::format("multigrid: a {}x{} matrix for {} free DOFs", A.rows(), A.cols(), impl_->row_dof.size()));
  const std::uint64_t pattern = pattern_hash(A);
  if (!impl_->have_structure || pattern != impl_->pattern) {
    impl_->structure(A);
    impl_->coarse_current = false;
    impl_->pattern = pattern;
    impl_->have_structure = true;
  }
  return impl_->values(A, shift, coarse);
}

void MultigridPreconditioner::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) const { impl_->product(p, Ap); }

void MultigridPreconditioner::Impl::product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) {
  Level& L0 = levels.front();
  product_in.setZero(3 * L0.nodes);
  for (std::size_t k = 0; k < row_dof.size(); ++k) product_in[row_dof[k]] = p[static_cast<Eigen::Index>(k)];
  product_out.resize(3 * L0.nodes);
  subtract_product(L0, product_in.data(), product_out.data(), parallel(L0));
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

const std::vector<int>& MultigridPreconditioner::colours(int level) const { return impl_->levels.at(level).colour; }

std::vector<std::pair<int, int>> MultigridPreconditioner::couplings(int level) const {
  const Blocks& A = impl_->levels.at(level).A;
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i + 1 < A.start.size(); ++i)
    for (int s = A.start[i]; s < A.start[i + 1]; ++s)
      if (A.col[s] != static_cast<int>(i)) out.emplace_back(static_cast<int>(i), A.col[s]);
  return out;
}

Eigen::SparseMatrix<double> MultigridPreconditioner::level_matrix(int level) const {
  const Level& L = impl_->levels.at(level);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < L.nodes; ++i)
    for (int s = L.A.start[i]; s < L.A.start[i + 1]; ++s) {
      const int j = L.A.col[s];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double v = L.A.val[9 * static_cast<std::size_t>(s) + 3 * a + b];
          entries.emplace_back(3 * i + a, 3 * j + b, v);
          if (j != i) entries.emplace_back(3 * j + b, 3 * i + a, v);
        }
    }
  Eigen::SparseMatrix<double> M(3 * L.nodes, 3 * L.nodes);
  M.setFromTriplets(entries.begin(), entries.end());
  return M;
}

Eigen::SparseMatrix<double> MultigridPreconditioner::prolongation(int level) const {
  const Level& F = impl_->levels.at(level);
  const Level& C = impl_->levels.at(level + 1);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < F.nodes; ++i)
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          entries.emplace_back(3 * i + a, 3 * F.down.node[p] + b, F.down.block[9 * static_cast<std::size_t>(p) + 3 * a + b]);
  Eigen::SparseMatrix<double> P(3 * F.nodes, 3 * C.nodes);
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

void MultigridPreconditioner::set_parallel_nodes(int nodes) { impl_->parallel_nodes = nodes; }

namespace {

class MultigridSolver final : public LinearSolver {
 public:
  MultigridSolver(const LinearSolverOptions& o, const SolverGeometry& g, Coarsening how)
      : how_(how), name_(how == Coarsening::lattice ? "mg" : "amg"), tolerance_(o.tolerance), vcycle_(mesh_of(g, name_), *g.free_index, how) {}
  bool try_factorize(const SparseLower& A) override {
    may_truncate_ = true;
    return compute(A);
  }
  double factorize(const SparseLower& A) override {
    may_truncate_ = false;
    if (compute(A)) return 0.0;
    // The direct solvers' search (linear_solver.hpp), on the V-cycle of A + σI.
    const double shift = search_diagonal_shift(A, [&](double s) { return vcycle_.compute(A, s); });
    if (!std::isnan(shift)) return shift;
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be made positive definite by a diagonal shift (it has a non-finite entry)", name_));
  }
  /// Conjugate gradients on the matrix the V-cycle holds (A, plus the shift factorize() added).
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, b.size() / 10));
    Eigen::VectorXd x;
    const MatrixProduct A = [this](const Eigen::VectorXd& p, Eigen::VectorXd& Ap) { vcycle_.multiply(p, Ap); };
    const CgResult r = conjugate_gradients(A, b, vcycle_, std::max(tolerance_ * b.norm(), enough), max_iterations, x);
    iterations_ = r.iterations;
    if (fresh_iterations_ < 0) fresh_iterations_ = r.iterations;
    // Truncated Newton (Nocedal and Wright, Algorithm 7.1): a matrix given to try_factorize() that shows
    // negative curvature after the first CG step yields the iterate before it, if that already solves the
    // system to half of ‖b‖ (an inexact Newton step of forcing ½). Measured on the flesh benchmark's hardest
    // step (45 272 hexes, inverted cells; truncated at a residual of 0.22): 15 Newton iterations, ten of them
    // on the projected Hessian after a failed true one, became 6, to the same energy. Without the residual
    // rule, boxes squashed through themselves took up to 3.8x the iterations (truncations at residuals up to
    // 138 ‖b‖); with it, the same as without truncation (tests/solve/test_multigrid.cpp).
    truncated_ = may_truncate_ && r.status == CgStatus::indefinite && r.iterations > 1 && r.residual <= 0.5 * b.norm();
    if (truncated_) return x;
    return r.status == CgStatus::converged ? x : Eigen::VectorXd::Constant(b.size(), std::nan(""));
  }
  bool last_truncated() const override { return truncated_; }
  int last_iterations() const override { return iterations_; }
  std::string_view name() const override { return name_; }
  bool inexact() const override { return true; }

 private:
  static const VolumeMesh& mesh_of(const SolverGeometry& g, std::string_view name) {
    if (!g.mesh || !g.free_index)
      throw std::invalid_argument(fmt::format("the multigrid solver ({}) needs the mesh behind the matrix (use cholmod, ldlt or pcg)", name));
    return *g.mesh;
  }
  /// The V-cycle for A. Both keep their coarse levels (the costly part: the Galerkin products, amg's smoothed
  /// P, the coarsest factorization) from an earlier Newton matrix while the last solve needed at most half
  /// as many iterations again as the first solve after they were made. (mg made them for every matrix until
  /// measured: hex stretch res 30 10.0 -> 8.8 s, a hand lattice's frame 2.2 -> 1.7 s.)
  bool compute(const SparseLower& A) {
    const bool coarse = fresh_iterations_ < 0 || 2 * iterations_ > 3 * fresh_iterations_;
    if (coarse) fresh_iterations_ = -1;
    if (vcycle_.compute(A, 0.0, coarse)) return true;
    fresh_iterations_ = -1;  // factorize() then shifts: the coarse levels are made for each shifted try
    return false;
  }
  Coarsening how_;
  std::string_view name_;
  double tolerance_;
  int fresh_iterations_ = -1;  ///< iterations of the first solve with the current coarse levels (−1: none yet)
  MultigridPreconditioner vcycle_;
  int iterations_ = 0;
  bool may_truncate_ = false;  ///< the matrix came from try_factorize() (it may be indefinite)
  bool truncated_ = false;     ///< the last solve was truncated at non-positive curvature
};

}  // namespace

std::unique_ptr<LinearSolver> make_multigrid_solver(const LinearSolverOptions& options, const SolverGeometry& geometry) {
  return std::make_unique<MultigridSolver>(options, geometry, Coarsening::lattice);
}

bool amg_applicable(const SolverGeometry& geometry) {
  return geometry.mesh && geometry.free_index && geometry.free_index->size() == 3 * static_cast<std::size_t>(geometry.mesh->vertex_count());
}

std::unique_ptr<LinearSolver> make_amg_solver(const LinearSolverOptions& options, const SolverGeometry& geometry) {
  return std::make_unique<MultigridSolver>(options, geometry, Coarsening::aggregation);
}

}  // namespace snh
