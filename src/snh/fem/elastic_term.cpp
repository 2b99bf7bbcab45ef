#include "snh/fem/elastic_term.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

#include <fmt/format.h>

#include "snh/fem/buckets.hpp"
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

/// Whether M gives its analytic Hessian as weighted slices (energies of I2 and I3: InvariantEnergy).
template <class M>
constexpr bool has_hessian_slices = requires(const M& m, const Mat3& F) { m.weighted_hessian_slices(F, 1.0); };

/// Energy, gradient (3 by N) and packed stiffness (packed_size<N> values) of one element at node positions X.
template <class M, int N, int Q>
double element_terms(const M& m, const ElementRest<N, Q>& r, const Eigen::Matrix<double, 3, N>& X,
                     Eigen::Matrix<double, 3, N>* grad, double* K, PsdProjection p) {
  double psi = 0.0;
  if (grad) grad->setZero();
  if (K) std::fill(K, K + packed_size<N>, 0.0);
  // The analytic Hessian of an energy of the invariants comes as its six slices straight from its formula,
  // the same values as the 9x9 matrix scaled by w (tested), without building it (bench_assembly: the true
  // Hessian's assembly 2.97 -> 2.47 us per hex).
  constexpr bool sliced = has_hessian_slices<M>;
  const bool slices = sliced && K && p == PsdProjection::none;
  for (int q = 0; q < Q; ++q) {
    const Eigen::Matrix<double, N, 3>& G = r.G[q];
    const double w = r.weight[q];
    const Mat3 F = X * G;
    PointTerms t = point_terms(m, F, grad != nullptr, K != nullptr && !slices, p);  // one SVD at most
    psi += w * t.psi;
    if (grad) grad->noalias() += (w * t.P) * G.transpose();
    if (!K) continue;
    if constexpr (sliced) {
      if (slices) {
        const std::array<Mat3, 6> h = m.weighted_hessian_slices(F, w);
        add_point_stiffness<N>(G, [&h](int i, int k, int j, int l) { return h[packed_pair(i, k)](j, l); }, K);
        continue;
      }
    }
    t.H *= w;
    add_point_stiffness<N>(G, [&t](int i, int k, int j, int l) { return t.H(3 * j + i, 3 * l + k); }, K);
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
  const Eigen::Index n = mesh_.vertex_count();
  const int npc = nodes_per_cell(mesh_.type);

  // Vertex -> cells adjacency.
  const Buckets vertex_cells = bucket(static_cast<int>(n), [&](auto&& emit) {
    for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c)
      for (int a = 0; a < npc; ++a) emit(mesh_.cells(a, c), static_cast<int>(c));
  });
  const std::vector<int>& vc_start = vertex_cells.start;
  const std::vector<int>& vc_list = vertex_cells.items;

  // Greedy colouring: an element takes the smallest colour unused by elements sharing a vertex.
  std::vector<int> colour(mesh_.cell_count(), -1), stamp;
  int colours = 0;
  for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c) {
    for (int a = 0; a < npc; ++a) {
      const int v = mesh_.cells(a, c);
      for (int i = vc_start[v]; i < vc_start[v + 1]; ++i) {
        const int other = colour[vc_list[i]];
        if (other >= 0) {
          if (other >= static_cast<int>(stamp.size())) stamp.resize(other + 1, -1);
          stamp[other] = static_cast<int>(c);
        }
      }
    }
    int pick = 0;
    while (pick < static_cast<int>(stamp.size()) && stamp[pick] == static_cast<int>(c)) ++pick;
    colour[c] = pick;
    colours = std::max(colours, pick + 1);
  }
  // Groups of cells of one colour and one material, colour-major: group k M + m.
  const int M = static_cast<int>(materials_.size());
  Buckets groups = bucket(colours * M, [&](auto&& emit) {
    for (std::size_t c = 0; c < colour.size(); ++c)
      emit(colour[c] * M + (material_of_.empty() ? 0 : material_of_[c]), static_cast<int>(c));
  });
  group_start_ = std::move(groups.start);
  group_cells_ = std::move(groups.items);
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
    std::visit([&](const auto& m, const auto& rest) { body(m, rest, group_cells_.data() + begin, Eigen::Index{end - begin}); },
               materials_[g % M], rest_);
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

std::vector<int> ElasticTerm::scatter_map(const HessianLayout& layout) const {
  // For each element and packed entry K_ik(a, b) (the DOFs A = 3a+i and B = 3b+k, i >= k), the value index
  // of (max(num(A), num(B)), min(...)) when both are numbered; −1 otherwise, and for a < b in K_ii (the
  // same pair as K_ii(b, a)).
  return std::visit(
      [&](const auto& rest) {
        constexpr int N = std::decay_t<decltype(rest)>::value_type::nodes;
        const std::vector<int>& num = layout.numbering();
        std::vector<int> scatter(static_cast<std::size_t>(mesh_.cell_count()) * packed_size<N>, -1);
        for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c) {
          int* map = scatter.data() + static_cast<std::size_t>(c) * packed_size<N>;
          for (int i = 0; i < 3; ++i)
            for (int k = 0; k <= i; ++k)
              for (int b = 0; b < N; ++b)
                for (int a = i == k ? b : 0; a < N; ++a) {
                  const int rA = num[3 * mesh_.cells(a, c) + i], rB = num[3 * mesh_.cells(b, c) + k];
                  if (rA < 0 || rB < 0) continue;
                  const int e = layout.entry(std::max(rA, rB), std::min(rA, rB));
                  if (e < 0) throw std::logic_error("elastic term: the layout does not hold an element's entries");
                  map[N * N * packed_pair(i, k) + N * b + a] = e;
                }
        }
        return scatter;
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
  // Group by group (colour-major): the cells of a group share no vertex, so each element adds its terms
  // straight into the gradient and the values without two threads touching the same entry, and each entry
  // receives its terms in group order for any thread count.
  // A stiffness costs 5-10x an energy and gradient per point (bench_assembly), so it goes parallel with
  // an eighth of the points: tet res 20's colour groups (1 548 tets) ran on one thread.
  const Eigen::Index threshold = values ? parallel_threshold_ / 8 : parallel_threshold_;
  if (!gradient && !values) {
    // The energy alone adds into no vertex: the cells in their own order, not by colour groups whose cells lie
    // apart (Figure 1's lattice: the guesses, five energies a step, 0.10-0.13 -> 0.09-0.10 s). Bit-identical:
    // the same per-cell values, summed in the same order.
    for_each_run([&](const auto& m, const auto& rest, Eigen::Index begin, Eigen::Index end) {
      using R = typename std::decay_t<decltype(rest)>::value_type;
      Eigen::Matrix<double, 3, R::nodes>* const no_gradient = nullptr;
      ParallelErrors errors;
#pragma omp parallel for schedule(static) if ((end - begin) * R::points >= threshold)
      for (Eigen::Index c = begin; c < end; ++c)
        errors.run(c, [&] {
          per[static_cast<std::size_t>(c)] = element_terms(m, rest[record(c)], gather_nodes<R::nodes>(mesh_, c, x),
                                                           no_gradient, nullptr, projection);
        });
      errors.rethrow();
    });
  } else {
    for_each_group([&](const auto& m, const auto& rest, const int* list, Eigen::Index count) {
      using R = typename std::decay_t<decltype(rest)>::value_type;
      constexpr int N = R::nodes;
      ParallelErrors errors;
#pragma omp parallel for schedule(static) if (count * R::points >= threshold)
      for (Eigen::Index i = 0; i < count; ++i) {
        errors.run(i, [&] {
          const int c = list[i];
          Eigen::Matrix<double, 3, N> gc;
          std::array<double, packed_size<N>> K;
          per[static_cast<std::size_t>(c)] = element_terms(m, rest[record(c)], gather_nodes<N>(mesh_, c, x),
                                                           gradient ? &gc : nullptr, values ? K.data() : nullptr, projection);
          if (gradient)
            for (int a = 0; a < N; ++a) gradient->segment<3>(3 * mesh_.cells(a, c)) += gc.col(a);
          if (values) {
            const int* map = scatter->data() + static_cast<std::size_t>(c) * packed_size<N>;
            for (int e = 0; e < packed_size<N>; ++e)
              if (map[e] >= 0) values[map[e]] += K[static_cast<std::size_t>(e)];
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
        const Mat3 F = X * r.G[q];
        const double J = F.determinant();
        lo = std::min(lo, J);
        vol += r.weight[q] * J;
        psi += r.weight[q] * m.psi(F);
        weight += r.weight[q];
      }
      out.min_J[c] = lo;
      out.energy_density[c] = psi / weight;
      volume[c] = vol;
    }
  });
  out.volume = volume.sum();  // a fixed order for any thread count
  return out;
}

}  // namespace snh
