#include "snh/fem/elastic_term.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <unordered_map>

#ifdef __AVX512F__
#include <immintrin.h>
#endif

#include <fmt/format.h>

#include "snh/fem/buckets.hpp"
#include "snh/material/eigensystem.hpp"
#include "snh/math/parallel.hpp"

namespace snh {
namespace {

/// The mesh, after checking that every cell refers to existing vertices (before anything indexes by them).
VolumeMesh checked(VolumeMesh mesh) {
  const Eigen::Index n = mesh.vertex_count();
  if (mesh.cells.rows() != nodes_per_cell(mesh.type)) throw std::invalid_argument("cells do not match the cell type");
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (Eigen::Index a = 0; a < mesh.cells.rows(); ++a)
      if (mesh.cells(a, c) < 0 || mesh.cells(a, c) >= n)
        throw std::invalid_argument(fmt::format("cell {} refers to vertex {} (mesh has {})", c, mesh.cells(a, c), n));
  // The packed stiffness holds each pair of a cell's DOFs once: a vertex twice in a cell would need two.
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (Eigen::Index a = 0; a < mesh.cells.rows(); ++a)
      for (Eigen::Index b = 0; b < a; ++b)
        if (mesh.cells(a, c) == mesh.cells(b, c))
          throw std::invalid_argument(fmt::format("cell {}: vertex {} appears twice", c, mesh.cells(a, c)));
  return mesh;
}

/// The stiffness of an element with N nodes is kept as six N by N matrices K_ik, i >= k (it is symmetric):
/// K_ik(a, b) is the entry of the DOFs 3a+i and 3b+k, at N² packed_pair(i, k) + N b + a. Each holds whole
/// columns over the nodes, so that the products below run on vectors of N doubles.
template <int N>
constexpr int packed_size = 6 * N * N;
constexpr int packed_pair(int i, int k) { return i * (i + 1) / 2 + k; }

/// Adds the stiffness of one quadrature point to the packed K: with vec(F)_{3j+i} = Σ_a x_{a,i} G_{a,j},
/// K_ik(a, b) = w Σ_{j,l} G_{a,j} H_{3j+i,3l+k} G_{b,l}, that is K_ik = G H_ik Gᵀ with H_ik the 3x3 matrix
/// (j, l) ↦ w H_{3j+i,3l+k}, which slice(i, k, j, l) gives.
template <int N, class Slice>
void add_point_stiffness(const Eigen::Matrix<double, N, 3>& G, const Slice& slice, double* K) {
  using NxN = Eigen::Matrix<double, N, N>;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k <= i; ++k) {
      Eigen::Matrix<double, N, 3> GH;
      for (int l = 0; l < 3; ++l)
        GH.col(l) = G.col(0) * slice(i, k, 0, l) + G.col(1) * slice(i, k, 1, l) + G.col(2) * slice(i, k, 2, l);
      Eigen::Map<NxN> Kik(K + N * N * packed_pair(i, k));
      for (int b = 0; b < N; ++b) Kik.col(b) += GH.col(0) * G(b, 0) + GH.col(1) * G(b, 1) + GH.col(2) * G(b, 2);
    }
}

/// Eight doubles (GCC's and Clang's vector extensions: one AVX-512 register) and a · b + c on them, fused where
/// the CPU has AVX-512 (the build does not contract a * b + c itself: see CMakeLists.txt).
using Lanes8 = double __attribute__((vector_size(64)));
inline Lanes8 multiply_add(Lanes8 a, double b, Lanes8 c) {
#ifdef __AVX512F__
  return Lanes8(_mm512_fmadd_pd(__m512d(a), _mm512_set1_pd(b), __m512d(c)));
#else
  return a * b + c;
#endif
}
inline Lanes8 load8(const double* p) {
  Lanes8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

/// Adds the stiffness of all Q points of a hexahedron (N = 8: a column over its nodes is one Lanes8) from their
/// weighted Hessian slices h[q], as add_point_stiffness() for every q: K_ik = Σ_q G_q h_q,ik G_qᵀ. Column b of
/// K_ik is Σ_{q,l} (G_q h_q,ik)_{·,l} G_q(b, l): eight sums in registers over the 3Q columns of the G_q h_q,ik,
/// each made once and used for all eight, and K_ik stored once (not loaded, added and stored per point).
template <int Q>
void add_hex_stiffness(const ElementRest<8, Q>& r, const std::array<HessianSlices, Q>& h, double* K) {
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k <= i; ++k) {
      const int pair = packed_pair(i, k);
      Lanes8 sum[8] = {};
      for (int q = 0; q < Q; ++q) {
        const double* G = r.G[static_cast<std::size_t>(q)].data();  // column-major: column j at G + 8 j
        const Lanes8 g0 = load8(G), g1 = load8(G + 8), g2 = load8(G + 16);
        const Mat3& s = h[static_cast<std::size_t>(q)][static_cast<std::size_t>(pair)];
        for (int l = 0; l < 3; ++l) {
          const Lanes8 column = multiply_add(g2, s(2, l), multiply_add(g1, s(1, l), g0 * s(0, l)));  // (G_q s)_{·,l}
          for (int b = 0; b < 8; ++b) sum[b] = multiply_add(column, G[8 * l + b], sum[b]);
        }
      }
      double* Kik = K + 64 * pair;
      for (int b = 0; b < 8; ++b) {
        const Lanes8 v = load8(Kik + 8 * b) + sum[b];
        std::memcpy(Kik + 8 * b, &v, sizeof v);
      }
    }
}

/// F = X G (the element's deformation gradient at a point), summed over the nodes in order: inline, where
/// Eigen's product of a 3×N by an N×3 matrix was a function call per quadrature point.
template <int N>
inline Mat3 deformation_gradient(const Eigen::Matrix<double, 3, N>& X, const Eigen::Matrix<double, N, 3>& G) {
  Mat3 F;
  for (int j = 0; j < 3; ++j) {
    Vec3 c = X.col(0) * G(0, j);
    for (int a = 1; a < N; ++a) c += X.col(a) * G(a, j);
    F.col(j) = c;
  }
  return F;
}

/// Whether M gives its analytic Hessian as weighted slices (energies of I2 and I3: InvariantEnergy).
template <class M>
constexpr bool has_hessian_slices = requires(const M& m, const Mat3& F) { m.weighted_hessian_slices(F, 1.0); };

/// Energy, gradient (3 by N) and packed stiffness (packed_size<N> values) of one element at node positions X.
/// A muscle point's terms: the material and the fibre on the elastic part F A, pulled back to F
/// (docs/math.md §14.2).
template <class M>
PointTerms muscle_point_terms(const M& m, const CellFibre& f, const Mat3& F, bool want_P, bool want_H, PsdProjection p) {
  const Mat3 E = f.active.elastic(F);
  PointTerms t = point_terms(m, E, want_P, want_H, p);
  t.psi += f.energy.psi(E, f.direction);
  if (want_P) t.P = f.active.pk1(t.P + f.energy.pk1(E, f.direction));
  if (want_H) t.H = f.active.hessian(t.H + f.energy.projected_hessian(E, f.direction, p));
  return t;
}

template <class M, int N, int Q>
double element_terms(const M& m, const ElementRest<N, Q>& r, const Eigen::Matrix<double, 3, N>& X,
                     Eigen::Matrix<double, 3, N>* grad, double* K, PsdProjection p, const CellFibre* fibre = nullptr) {
  double psi = 0.0;
  if (grad) grad->setZero();
  if (K) std::fill(K, K + packed_size<N>, 0.0);
  // The analytic Hessian of an energy of the invariants comes as its six slices straight from its formula,
  // the same values as the 9x9 matrix scaled by w (tested), without building it (cheaper: bench_assembly,
  // docs/results.md). A projected one is those slices plus the change of the eigenvalues the projection
  // alters (add_projection_change: none where the point's Hessian is positive semi-definite), again without
  // the 9x9 matrix. A muscle cell's Hessian is the whole 9x9 matrix, pulled back through its active strain.
  constexpr bool sliced = has_hessian_slices<M>;
  const bool slices = sliced && K && !fibre;
  std::array<HessianSlices, Q> h;  // the points' slices (sliced Hessians)
  for (int q = 0; q < Q; ++q) {
    const Eigen::Matrix<double, N, 3>& G = r.G[q];
    const double w = r.weight[q];
    const Mat3 F = deformation_gradient<N>(X, G);
    PointTerms t = fibre ? muscle_point_terms(m, *fibre, F, grad != nullptr, K != nullptr, p)
                         : point_terms(m, F, grad != nullptr, K != nullptr && !slices, p);  // one SVD at most
    psi += w * t.psi;
    if (grad) grad->noalias() += (w * t.P) * G.transpose();
    if (!K) continue;
    if constexpr (sliced) {
      if (slices) {
        HessianSlices& hq = h[static_cast<std::size_t>(q)];
        hq = m.weighted_hessian_slices(F, w);
        if (p != PsdProjection::none) {
          const Svd3 svd = rotation_variant_svd(F);
          if (m.defined_sigma(svd.sigma)) (void)add_projection_change(svd, m.sigma_eigenvalues(svd.sigma), p, w, hq);
          else for (Mat3& slice : hq) slice.setZero();
        }
        continue;
      }
    }
    t.H *= w;
    add_point_stiffness<N>(G, [&t](int i, int k, int j, int l) { return t.H(3 * j + i, 3 * l + k); }, K);
  }
  if constexpr (N == 8) {
    if (slices) add_hex_stiffness<Q>(r, h, K);
  } else if (slices) {
    for (int q = 0; q < Q; ++q) {
      const auto& hq = h[static_cast<std::size_t>(q)];
      add_point_stiffness<N>(r.G[q], [&hq](int i, int k, int j, int l) { return hq[packed_pair(i, k)](j, l); }, K);
    }
  }
  return psi;
}

template <int N>
Eigen::Matrix<double, 3, N> gather_nodes(const VolumeMesh& mesh, Eigen::Index c, const Eigen::VectorXd& x) {
  Eigen::Matrix<double, 3, N> X;
  for (int a = 0; a < N; ++a) X.col(a) = x.segment<3>(3 * mesh.cells(a, c));
  return X;
}

/// Checks that every cell's material index is below `materials`.
void check_material_indices(const std::vector<int>& material_of, std::size_t materials) {
  for (std::size_t c = 0; c < material_of.size(); ++c) {
    const int m = material_of[c];
    if (m < 0 || static_cast<std::size_t>(m) >= materials)
      throw std::invalid_argument(fmt::format("cell {}: material index {} (there are {} materials)", c, m, materials));
  }
}

/// The rest state with each cell's quadrature weights multiplied by its scale.
RestState scaled(RestState rest, const Eigen::VectorXd& scale) {
  if (scale.size() == 0) return rest;
  std::visit(
      [&](auto& elems) {
        if (static_cast<Eigen::Index>(elems.size()) != scale.size())
          throw std::invalid_argument(fmt::format("weight scales: expected {} (one per cell), got {}", elems.size(), scale.size()));
        for (std::size_t c = 0; c < elems.size(); ++c) {
          const double s = scale[static_cast<Eigen::Index>(c)];
          if (!(s > 0.0) || !std::isfinite(s))
            throw std::invalid_argument(fmt::format("cell {}: weight scale must be a finite number > 0, got {}", c, s));
          for (double& w : elems[c].weight) w *= s;
        }
      },
      rest);
  return rest;
}

/// The key under which cells share a rest record: its shape gradients and its weights, each set in units of
/// 2^-40 of its largest magnitude's power of two (with those powers). Records of one key differ by less than
/// that unit in every value: a lattice's congruent cells, equal but for the rounding of their vertices'
/// coordinates (a relative 1e-14 in G, against the unit's 9e-13).
template <int N, int Q>
std::vector<std::int64_t> sharing_key(const ElementRest<N, Q>& r) {
  std::vector<std::int64_t> key;
  key.reserve(3 * N * Q + Q + 2);
  const auto add = [&key](const double* v, int n) {
    double largest = 0.0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, std::abs(v[i]));
    const int power = largest > 0.0 ? std::ilogb(largest) : 0;
    key.push_back(power);
    for (int i = 0; i < n; ++i) key.push_back(std::llround(std::ldexp(v[i], 40 - power)));
  };
  for (int q = 0; q < Q; ++q) add(r.G[q].data(), 3 * N);
  add(r.weight.data(), Q);
  return key;
}

struct KeyHash {
  std::size_t operator()(const std::vector<std::int64_t>& key) const {
    std::uint64_t h = 1469598103934665603ULL;
    for (std::int64_t v : key) h = (h ^ static_cast<std::uint64_t>(v)) * 1099511628211ULL;
    return static_cast<std::size_t>(h);
  }
};

}  // namespace

ElasticTerm::ElasticTerm(VolumeMesh mesh, AnyMaterial material)
    : ElasticTerm(std::move(mesh), std::vector<AnyMaterial>{std::move(material)}, {}) {}

ElasticTerm::ElasticTerm(VolumeMesh mesh, std::vector<AnyMaterial> materials, std::vector<int> material_of_cell,
                         Eigen::VectorXd weight_scale)
    : mesh_(checked(std::move(mesh))),
      materials_(std::move(materials)),
      material_of_(std::move(material_of_cell)),
      rest_(scaled(compute_rest_state(mesh_), weight_scale)) {
  if (materials_.empty()) throw std::invalid_argument("no material given");
  share_rest(true);
  if (!material_of_.empty()) {
    if (static_cast<Eigen::Index>(material_of_.size()) != mesh_.cell_count())
      throw std::invalid_argument(fmt::format("materials per cell: expected {}, got {}", mesh_.cell_count(), material_of_.size()));
    check_material_indices(material_of_, materials_.size());
  } else if (materials_.size() > 1) {
    throw std::invalid_argument("several materials need a material index per cell");
  }
  set_chunk_cells(-1);
}

void ElasticTerm::set_chunk_cells(Eigen::Index chunk) {
  const Eigen::Index cells = mesh_.cell_count(), n = mesh_.vertex_count();
  const int npc = nodes_per_cell(mesh_.type);
  if (chunk < 0) chunk = std::max<Eigen::Index>(1024, cells / 64);

  // Vertex -> cells adjacency.
  const Buckets vertex_cells = bucket(static_cast<int>(n), [&](auto&& emit) {
    for (Eigen::Index c = 0; c < cells; ++c)
      for (int a = 0; a < npc; ++a) emit(mesh_.cells(a, c), static_cast<int>(c));
  });
  const std::vector<int>& vc_start = vertex_cells.start;
  const std::vector<int>& vc_list = vertex_cells.items;

  // Greedy colouring of units of cells (chunks of consecutive cells, or single cells): a unit takes the
  // smallest colour unused by the earlier units it shares a vertex with.
  const auto colour_units = [&](Eigen::Index size, std::vector<int>& colour) {
    const Eigen::Index units = (cells + size - 1) / size;
    colour.assign(static_cast<std::size_t>(units), -1);
    std::vector<Eigen::Index> stamp;
    int colours = 0;
    for (Eigen::Index u = 0; u < units; ++u) {
      for (Eigen::Index c = u * size; c < std::min(cells, (u + 1) * size); ++c)
        for (int a = 0; a < npc; ++a) {
          const int v = mesh_.cells(a, c);
          for (int i = vc_start[v]; i < vc_start[v + 1]; ++i) {
            const Eigen::Index other = vc_list[i] / size;
            if (other >= u) continue;
            const int k = colour[static_cast<std::size_t>(other)];
            if (k >= static_cast<int>(stamp.size())) stamp.resize(k + 1, -1);
            stamp[k] = u;
          }
        }
      int pick = 0;
      while (pick < static_cast<int>(stamp.size()) && stamp[pick] == u) ++pick;
      colour[static_cast<std::size_t>(u)] = pick;
      colours = std::max(colours, pick + 1);
    }
    return colours;
  };
  // Chunks where they need few colours (a lattice's cells in grid order: slabs, two colours), else cells.
  std::vector<int> colour;
  int colours = 0;
  chunk_cells_ = 1;
  if (chunk > 1 && cells >= 4 * chunk) {
    colours = colour_units(chunk, colour);
    if (colours <= kMaxChunkColours) chunk_cells_ = chunk;
  }
  if (chunk_cells_ == 1) colours = colour_units(1, colour);
  // Groups of cells of one colour and one material, colour-major: group k M + m, each cut into pieces that
  // one thread runs in cell order: its chunks, or runs of kCellsPerPiece of its cells (which share no vertex).
  const int M = static_cast<int>(materials_.size());
  Buckets groups = bucket(colours * M, [&](auto&& emit) {
    for (Eigen::Index c = 0; c < cells; ++c)
      emit(colour[static_cast<std::size_t>(c / chunk_cells_)] * M + (material_of_.empty() ? 0 : material_of_[static_cast<std::size_t>(c)]),
           static_cast<int>(c));
  });
  group_start_ = std::move(groups.start);
  group_cells_ = std::move(groups.items);
  piece_start_.clear();
  group_pieces_.assign(1, 0);
  for (std::size_t g = 0; g + 1 < group_start_.size(); ++g) {
    for (int i = group_start_[g]; i < group_start_[g + 1]; ++i)
      if (i == group_start_[g] || (chunk_cells_ > 1 ? group_cells_[i] / chunk_cells_ != group_cells_[i - 1] / chunk_cells_
                                                    : (i - group_start_[g]) % kCellsPerPiece == 0))
        piece_start_.push_back(i);
    group_pieces_.push_back(static_cast<int>(piece_start_.size()));
  }
  piece_start_.push_back(static_cast<int>(group_cells_.size()));
}

void ElasticTerm::share_rest(bool on) {
  const RestState per_cell = rest_of_cell_.empty() ? std::move(rest_) : rest();  // the constructor's: one per cell
  std::visit(
      [&](const auto& cells) {
        std::decay_t<decltype(cells)> records;
        rest_of_cell_.resize(cells.size());
        std::unordered_map<std::vector<std::int64_t>, int, KeyHash> first;
        for (std::size_t c = 0; c < cells.size(); ++c) {
          const int next = static_cast<int>(records.size());
          const int k = on ? first.try_emplace(sharing_key(cells[c]), next).first->second : next;
          if (k == next) records.push_back(cells[c]);
          rest_of_cell_[c] = k;
        }
        records.shrink_to_fit();
        rest_ = std::move(records);
      },
      per_cell);
}

int ElasticTerm::rest_records() const {
  return std::visit([](const auto& records) { return static_cast<int>(records.size()); }, rest_);
}

RestState ElasticTerm::rest() const {
  return std::visit(
      [&](const auto& records) -> RestState {
        typename std::decay_t<decltype(records)> cells;
        cells.reserve(rest_of_cell_.size());
        for (int k : rest_of_cell_) cells.push_back(records[static_cast<std::size_t>(k)]);
        return cells;
      },
      rest_);
}

Eigen::VectorXd ElasticTerm::rest_volumes() const {
  const Eigen::VectorXd of_record = snh::rest_volumes(rest_);
  Eigen::VectorXd volume(static_cast<Eigen::Index>(rest_of_cell_.size()));
  for (std::size_t c = 0; c < rest_of_cell_.size(); ++c) volume[static_cast<Eigen::Index>(c)] = of_record[rest_of_cell_[c]];
  return volume;
}

template <class Body>
void ElasticTerm::for_each_group(Body&& body) const {
  const std::size_t M = materials_.size();
  for (std::size_t g = 0; g + 1 < group_start_.size(); ++g) {
    const int begin = group_start_[g], end = group_start_[g + 1];
    if (begin == end) continue;
    std::visit([&](const auto& m, const auto& rest) {
      body(m, rest, piece_start_.data() + group_pieces_[g], Eigen::Index{group_pieces_[g + 1] - group_pieces_[g]}, Eigen::Index{end - begin});
    }, materials_[g % M], rest_);
  }
}

template <class Body>
void ElasticTerm::for_each_run(Body&& body) const {
  const Eigen::Index n = mesh_.cell_count();
  for (Eigen::Index begin = 0; begin < n;) {
    const int material = material_of_.empty() ? 0 : material_of_[static_cast<std::size_t>(begin)];
    Eigen::Index end = material_of_.empty() ? n : begin + 1;
    while (end < n && material_of_[static_cast<std::size_t>(end)] == material) ++end;
    std::visit([&](const auto& m, const auto& rest) { body(m, rest, begin, end); }, materials_[static_cast<std::size_t>(material)], rest_);
    begin = end;
  }
}

void ElasticTerm::stencil(const Eigen::VectorXd&, Stencil& out) const {
  out.arity = nodes_per_cell(mesh_.type);
  out.vertices.assign(mesh_.cells.data(), mesh_.cells.data() + mesh_.cells.size());
}

void ElasticTerm::scatter_map(const HessianLayout& layout, std::vector<int>& scatter) const {
  // For each element and packed entry K_ik(a, b) (the DOFs A = 3a+i and B = 3b+k, i >= k), the value index
  // of (max(num(A), num(B)), min(...)) when both are numbered; −1 otherwise, and for a < b in K_ii (the
  // same pair as K_ii(b, a)).
  std::visit(
      [&](const auto& rest) {
        constexpr int N = std::decay_t<decltype(rest)>::value_type::nodes;
        const std::vector<int>& num = layout.numbering();
        scatter.resize(static_cast<std::size_t>(mesh_.cell_count()) * packed_size<N>);
        // Cells in parallel (each fills its own part; a rebuilt layout pays this for every cell, 13.5 million
        // look-ups at Figure 1's size); a missing entry is reported after the loop, not thrown inside it.
        bool missing = false;
#pragma omp parallel for schedule(static) reduction(|| : missing) if (mesh_.cell_count() >= 4096)
        for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c) {
          int* map = scatter.data() + static_cast<std::size_t>(c) * packed_size<N>;
          for (int i = 0; i < 3; ++i)
            for (int k = 0; k <= i; ++k)
              for (int b = 0; b < N; ++b)
                for (int a = 0; a < N; ++a) {
                  int& to = map[N * N * packed_pair(i, k) + N * b + a];
                  const int rA = num[3 * mesh_.cells(a, c) + i], rB = num[3 * mesh_.cells(b, c) + k];
                  if ((i == k && a < b) || rA < 0 || rB < 0) {
                    to = -1;
                    continue;
                  }
                  to = layout.entry(std::max(rA, rB), std::min(rA, rB));
                  missing = missing || to < 0;
                }
        }
        if (missing) throw std::logic_error("elastic term: the layout does not hold an element's entries");
      },
      rest_);
}

double ElasticTerm::energy(const Eigen::VectorXd& x) const {
  return assemble(x, nullptr, nullptr, nullptr, PsdProjection::none);
}

double ElasticTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                             PsdProjection projection) const {
  if (hessian && scatter_.empty() && mesh_.cell_count() > 0)
    throw std::logic_error("elastic term: evaluate with a Hessian before bind()");
  return assemble(x, gradient, hessian ? &scatter_ : nullptr, hessian ? hessian->values() : nullptr, projection);
}

void ElasticTerm::add_hessian(const Eigen::VectorXd& x, const std::vector<int>& scatter, double* values,
                              PsdProjection projection) const {
  (void)assemble(x, nullptr, &scatter, values, projection);
}

double ElasticTerm::assemble(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const std::vector<int>* scatter,
                             double* values, PsdProjection projection) const {
  std::vector<double> per(static_cast<std::size_t>(mesh_.cell_count()));
  if (!scatter) values = nullptr;
  // Group by group (colour-major), each group's pieces in parallel: the pieces of a group share no vertex, so
  // each element adds its terms straight into the gradient and the values without two threads touching the
  // same entry, and each entry receives its terms in group order, and within a piece in cell order, for any
  // thread count. Chunks of consecutive cells as pieces (a lattice's slabs) keep each thread's matrix rows and
  // vertices together (fewer colours of chunks assemble Figure 1's Hessian faster than many colours of
  // single cells: docs/results.md, "Assembly").
  // A stiffness costs several times an energy and gradient per point (bench_assembly), so it goes parallel
  // with an eighth of the points: otherwise the colour groups of mid-sized tet meshes ran on one thread.
  const Eigen::Index threshold = values ? parallel_threshold_ / 8 : parallel_threshold_;
  if (!gradient && !values) {
    // The energy alone adds into no vertex: the cells in their own order, not by colour groups whose cells lie
    // apart (a lattice's guesses ask several energies a step; cells in order stream memory in order).
    // Bit-identical: the same per-cell values, summed in the same order.
    for_each_run([&](const auto& m, const auto& rest, Eigen::Index begin, Eigen::Index end) {
      using R = typename std::decay_t<decltype(rest)>::value_type;
      Eigen::Matrix<double, 3, R::nodes>* const no_gradient = nullptr;
      ParallelErrors errors;
#pragma omp parallel for schedule(static) if ((end - begin) * R::points >= threshold)
      for (Eigen::Index c = begin; c < end; ++c)
        errors.run(c, [&] {
          per[static_cast<std::size_t>(c)] = element_terms(m, rest[record(c)], gather_nodes<R::nodes>(mesh_, c, x),
                                                           no_gradient, nullptr, projection, fibre(c));
        });
      errors.rethrow();
    });
  } else {
    for_each_group([&](const auto& m, const auto& rest, const int* pieces, Eigen::Index piece_count, Eigen::Index count) {
      using R = typename std::decay_t<decltype(rest)>::value_type;
      constexpr int N = R::nodes;
      ParallelErrors errors;
#pragma omp parallel for schedule(dynamic) if (count * R::points >= threshold)
      for (Eigen::Index p = 0; p < piece_count; ++p) {
        errors.run(p, [&] {
          Eigen::Matrix<double, 3, N> gc;
          std::array<double, packed_size<N>> K;
          for (int i = pieces[p]; i < pieces[p + 1]; ++i) {
            const int c = group_cells_[static_cast<std::size_t>(i)];
            per[static_cast<std::size_t>(c)] = element_terms(m, rest[record(c)], gather_nodes<N>(mesh_, c, x),
                                                             gradient ? &gc : nullptr, values ? K.data() : nullptr, projection,
                                                             fibre(c));
            if (gradient)
              for (int a = 0; a < N; ++a) gradient->segment<3>(3 * mesh_.cells(a, c)) += gc.col(a);
            if (values) {
              const int* map = scatter->data() + static_cast<std::size_t>(c) * packed_size<N>;
              for (int e = 0; e < packed_size<N>; ++e)
                if (map[e] >= 0) values[map[e]] += K[static_cast<std::size_t>(e)];
            }
          }
        });
      }
      errors.rethrow();
    });
  }
  double total = 0.0;
  for (double e : per) total += e;  // fixed order: deterministic
  return total;
}

void ElasticTerm::set_fibres(std::vector<int> fibre_of_cell, std::vector<CellFibre> fibres) {
  if (!fibre_of_cell.empty() && static_cast<Eigen::Index>(fibre_of_cell.size()) != mesh_.cell_count())
    throw std::invalid_argument(fmt::format("fibres: {} cells given, the mesh has {}", fibre_of_cell.size(), mesh_.cell_count()));
  for (std::size_t c = 0; c < fibre_of_cell.size(); ++c)
    if (fibre_of_cell[c] < -1 || fibre_of_cell[c] >= static_cast<int>(fibres.size()))
      throw std::invalid_argument(fmt::format("cell {}: fibre index {} (there are {} fibre sets)", c, fibre_of_cell[c], fibres.size()));
  for (std::size_t f = 0; f < fibres.size(); ++f) {
    const CellFibre& fib = fibres[f];
    if (!fib.direction.allFinite() || std::abs(fib.direction.norm() - 1.0) > 1e-12)
      throw std::invalid_argument(fmt::format("fibre set {}: the direction must be a unit vector", f));
    if (!(fib.energy.stiffness >= 0.0) || !std::isfinite(fib.energy.stiffness))
      throw std::invalid_argument(fmt::format("fibre set {}: the stiffness must be a finite number >= 0, got {}", f, fib.energy.stiffness));
  }
  fibre_of_ = std::move(fibre_of_cell);
  fibres_ = std::move(fibres);
}

void ElasticTerm::set_active_strain(int f, const ActiveStrain& active) {
  if (f < 0 || f >= static_cast<int>(fibres_.size()))
    throw std::invalid_argument(fmt::format("fibre set {} does not exist (there are {})", f, fibres_.size()));
  fibres_[static_cast<std::size_t>(f)].active = active;
}

ElasticTerm::Deformation ElasticTerm::deformation(const Eigen::VectorXd& x) const {
  Deformation out;
  out.min_J.resize(mesh_.cell_count());
  out.energy_density.resize(mesh_.cell_count());
  Eigen::VectorXd volume(mesh_.cell_count());
  for_each_run([&](const auto& m, const auto& rest, Eigen::Index begin, Eigen::Index end) {
    using R = typename std::decay_t<decltype(rest)>::value_type;
#pragma omp parallel for schedule(static) if ((end - begin) * R::points >= parallel_threshold_)
    for (Eigen::Index c = begin; c < end; ++c) {
      const auto X = gather_nodes<R::nodes>(mesh_, c, x);
      double lo = std::numeric_limits<double>::infinity(), psi = 0.0, weight = 0.0, vol = 0.0;
      const auto& r = rest[record(c)];
      for (int q = 0; q < R::points; ++q) {
        const Mat3 F = deformation_gradient<R::nodes>(X, r.G[q]);
        const double J = F.determinant();
        lo = std::min(lo, J);
        vol += r.weight[q] * J;
        const CellFibre* f = fibre(c);
        psi += r.weight[q] * (f ? muscle_point_terms(m, *f, F, false, false, PsdProjection::none).psi : m.psi(F));
        weight += r.weight[q];
      }
      out.min_J[c] = lo;
      out.energy_density[c] = psi / weight;
      volume[c] = vol;
    }
  });
  out.volume = volume.sum();  // a fixed order for any thread count
  if (!fibre_of_.empty()) {
    out.contraction = Eigen::VectorXd::Zero(mesh_.cell_count());
    for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c)
      if (const CellFibre* f = fibre(c)) out.contraction[c] = f->active.alpha;
  }
  return out;
}

}  // namespace snh
