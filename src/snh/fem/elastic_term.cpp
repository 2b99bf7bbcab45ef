#include "snh/fem/elastic_system.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

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
  return mesh;
}

/// Items grouped by an integer key in [0, keys), by counting sort: items[start[k] .. start[k+1]) have
/// key k, in the order emitted. for_each_pair(emit) must call emit(key, item) for every pair, the same
/// way each time (it is called twice: to count, then to fill).
struct Buckets {
  std::vector<int> start, items;
};
template <class ForEachPair>
Buckets bucket(int keys, ForEachPair&& for_each_pair) {
  Buckets b;
  b.start.assign(keys + 1, 0);
  for_each_pair([&](int key, int) { ++b.start[key + 1]; });
  for (int k = 0; k < keys; ++k) b.start[k + 1] += b.start[k];
  b.items.resize(b.start[keys]);
  std::vector<int> fill(b.start.begin(), b.start.end() - 1);
  for_each_pair([&](int key, int item) { b.items[fill[key]++] = item; });
  return b;
}

/// Energy, gradient (3 by N) and stiffness (3N by 3N, DOF 3a+i) of one element at node positions X.
template <class M, int N, int Q>
double element_terms(const M& m, const ElementRest<N, Q>& r, const Eigen::Matrix<double, 3, N>& X,
                     Eigen::Matrix<double, 3, N>* grad, Eigen::Matrix<double, 3 * N, 3 * N>* K, PsdProjection p) {
  double psi = 0.0;
  if (grad) grad->setZero();
  if (K) K->setZero();
  for (int q = 0; q < Q; ++q) {
    const Eigen::Matrix<double, N, 3>& G = r.G[q];
    const double w = r.weight[q];
    const Mat3 F = X * G;
    psi += w * m.psi(F);
    if (grad) grad->noalias() += (w * m.pk1(F)) * G.transpose();
    if (K) {
      // With vec(F)_{3j+i} = Σ_a x_{a,i} G_{a,j}: K_{(a,i),(b,k)} = w Σ_{j,l} G_{a,j} H_{3j+i,3l+k} G_{b,l}.
      const Mat9 H = w * projected_hessian(m, F, p);
      Eigen::Matrix<double, 9, 3 * N> HB;
      for (int b = 0; b < N; ++b)
        for (int k = 0; k < 3; ++k)
          HB.col(3 * b + k) = G(b, 0) * H.col(k) + G(b, 1) * H.col(3 + k) + G(b, 2) * H.col(6 + k);
      // Column c of K, read as a 3 by N matrix (i, a), is M_c Gᵀ with M_c the 3x3 matrix whose vec is
      // column c of HB: small dense products, contiguous in memory (measured faster than row blocks).
      const Eigen::Matrix<double, 3, N> Gt = G.transpose();
      for (int c = 0; c < 3 * N; ++c)
        Eigen::Map<Eigen::Matrix<double, 3, N>>(K->col(c).data()).noalias() +=
            Eigen::Map<const Mat3>(HB.col(c).data()) * Gt;
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

}  // namespace

ElasticSystem::ElasticSystem(VolumeMesh mesh, AnyMaterial material, std::vector<std::uint8_t> fixed)
    : mesh_(checked(std::move(mesh))), material_(std::move(material)), rest_(compute_rest_state(mesh_)) {
  const Eigen::Index n = mesh_.vertex_count();
  const int npc = nodes_per_cell(mesh_.type);
  if (static_cast<Eigen::Index>(fixed.size()) != 3 * n)
    throw std::invalid_argument(fmt::format("fixed flags: expected {} (3 per vertex), got {}", 3 * n, fixed.size()));

  // Free DOF numbering, increasing with the DOF index.
  free_index_.assign(3 * n, -1);
  for (Eigen::Index d = 0; d < 3 * n; ++d)
    if (!fixed[d]) free_index_[d] = static_cast<int>(free_count_++);

  // Vertex -> cells adjacency.
  const Buckets vertex_cells = bucket(static_cast<int>(n), [&](auto&& emit) {
    for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c)
      for (int a = 0; a < npc; ++a) emit(mesh_.cells(a, c), static_cast<int>(c));
  });
  const std::vector<int>& vc_start = vertex_cells.start;
  const std::vector<int>& vc_list = vertex_cells.items;

  // Vertex neighbours (sharing a cell, itself included), sorted.
  std::vector<std::vector<int>> nbr(n);
  for (Eigen::Index v = 0; v < n; ++v) {
    auto& list = nbr[v];
    for (int i = vc_start[v]; i < vc_start[v + 1]; ++i)
      for (int a = 0; a < npc; ++a) list.push_back(mesh_.cells(a, vc_list[i]));
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }

  // Lower-triangular CSC pattern over free DOFs: column c = free(3v+k) holds rows free(3u+l) >= c.
  std::vector<int> outer(free_count_ + 1, 0), inner;
  for (Eigen::Index v = 0; v < n; ++v)
    for (int k = 0; k < 3; ++k) {
      const int col = free_index_[3 * v + k];
      if (col < 0) continue;
      for (int u : nbr[v])
        for (int l = 0; l < 3; ++l) {
          const int row = free_index_[3 * u + l];
          if (row >= col) inner.push_back(row);
        }
      outer[col + 1] = static_cast<int>(inner.size());
    }
  nbr.clear();
  std::vector<double> zeros(inner.size(), 0.0);
  pattern_ = Eigen::Map<const SparseLower>(free_count_, free_count_, static_cast<Eigen::Index>(inner.size()),
                                           outer.data(), inner.data(), zeros.data());
  pattern_.makeCompressed();

  // Scatter map: for each element and local pair (A, B), at B·ld + A (the column-major layout of the
  // element stiffness), the value index of (free(A), free(B)) when both are free and free(A) >= free(B);
  // −1 otherwise (the symmetric partner is stored instead).
  const int ld = 3 * npc;
  scatter_.assign(static_cast<std::size_t>(mesh_.cell_count()) * ld * ld, -1);
  const int* out_ptr = pattern_.outerIndexPtr();
  const int* in_ptr = pattern_.innerIndexPtr();
  for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c)
    for (int A = 0; A < ld; ++A) {
      const int rA = free_index_[3 * mesh_.cells(A / 3, c) + A % 3];
      if (rA < 0) continue;
      for (int B = 0; B < ld; ++B) {
        const int rB = free_index_[3 * mesh_.cells(B / 3, c) + B % 3];
        if (rB < 0 || rA < rB) continue;
        const int* first = in_ptr + out_ptr[rB];
        const int* last = in_ptr + out_ptr[rB + 1];
        const int* it = std::lower_bound(first, last, rA);
        scatter_[(static_cast<std::size_t>(c) * ld + B) * ld + A] = static_cast<int>(it - in_ptr);
      }
    }

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
  Buckets by_colour = bucket(colours, [&](auto&& emit) {
    for (std::size_t c = 0; c < colour.size(); ++c) emit(colour[c], static_cast<int>(c));
  });
  colour_start_ = std::move(by_colour.start);
  colour_order_ = std::move(by_colour.items);
}

double ElasticSystem::energy(const Eigen::VectorXd& x) const {
  std::vector<double> per(mesh_.cell_count());
  std::visit(
      [&](const auto& m, const auto& rest) {
        using R = typename std::decay_t<decltype(rest)>::value_type;
        const Eigen::Index count = mesh_.cell_count();
#pragma omp parallel for schedule(static) if (count * R::points >= parallel_threshold_)
        for (Eigen::Index c = 0; c < count; ++c)
          per[c] = element_terms<std::decay_t<decltype(m)>, R::nodes, R::points>(
              m, rest[c], gather_nodes<R::nodes>(mesh_, c, x), nullptr, nullptr, PsdProjection::none);
      },
      material_, rest_);
  double total = 0.0;
  for (double e : per) total += e;  // fixed order: deterministic
  return total;
}

double ElasticSystem::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, SparseLower* hessian,
                               PsdProjection projection) const {
  const Eigen::Index count = mesh_.cell_count();
  std::vector<double> per(count);
  Eigen::VectorXd full = Eigen::VectorXd::Zero(x.size());
  if (hessian) {
    if (hessian->nonZeros() != pattern_.nonZeros() || hessian->rows() != pattern_.rows()) *hessian = pattern_;
    std::fill(hessian->valuePtr(), hessian->valuePtr() + hessian->nonZeros(), 0.0);
  }
  double* values = hessian ? hessian->valuePtr() : nullptr;
  std::visit(
      [&](const auto& m, const auto& rest) {
        using R = typename std::decay_t<decltype(rest)>::value_type;
        constexpr int N = R::nodes;
        constexpr int ld = 3 * N;
        // 1. Element terms, in one parallel loop, into per-element buffers (kept between calls: a fresh
        //    allocation of this size costs page faults every time).
        std::vector<double>& grads = grad_buffer_;
        std::vector<double>& stiff = stiffness_buffer_;
        grads.resize(static_cast<std::size_t>(count) * ld);
        if (values) stiff.resize(static_cast<std::size_t>(count) * ld * ld);
#pragma omp parallel for schedule(static) if (count * R::points >= parallel_threshold_)
        for (Eigen::Index c = 0; c < count; ++c) {
          Eigen::Map<Eigen::Matrix<double, 3, N>> g(grads.data() + static_cast<std::size_t>(c) * ld);
          Eigen::Matrix<double, ld, ld> K;
          Eigen::Matrix<double, 3, N> gc;
          per[c] = element_terms(m, rest[c], gather_nodes<N>(mesh_, c, x), &gc, values ? &K : nullptr, projection);
          g = gc;
          if (values) Eigen::Map<Eigen::Matrix<double, ld, ld>>(stiff.data() + static_cast<std::size_t>(c) * ld * ld) = K;
        }
        // 2. Scatter, colour by colour: elements of one colour share no vertex, so no two threads touch
        //    the same entry, and each entry receives its terms in colour order for any thread count.
        for (int k = 0; k + 1 < static_cast<int>(colour_start_.size()); ++k) {
          const int begin = colour_start_[k], end = colour_start_[k + 1];
#pragma omp parallel for schedule(static) if ((end - begin) * N >= parallel_threshold_)
          for (int i = begin; i < end; ++i) {
            const int c = colour_order_[i];
            const double* g = grads.data() + static_cast<std::size_t>(c) * ld;
            for (int a = 0; a < N; ++a) full.segment<3>(3 * mesh_.cells(a, c)) += Eigen::Map<const Eigen::Vector3d>(g + 3 * a);
            if (values) {
              const int* map = scatter_.data() + static_cast<std::size_t>(c) * ld * ld;
              const double* K = stiff.data() + static_cast<std::size_t>(c) * ld * ld;  // same layout as map
              for (int e = 0; e < ld * ld; ++e)
                if (map[e] >= 0) values[map[e]] += K[e];
            }
          }
        }
      },
      material_, rest_);
  gradient = gather_free(full);
  double total = 0.0;
  for (double e : per) total += e;
  return total;
}

Eigen::VectorXd ElasticSystem::gather_free(const Eigen::VectorXd& full) const {
  Eigen::VectorXd out(free_count_);
  for (std::size_t d = 0; d < free_index_.size(); ++d)
    if (free_index_[d] >= 0) out[free_index_[d]] = full[static_cast<Eigen::Index>(d)];
  return out;
}

void ElasticSystem::scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const {
  for (std::size_t d = 0; d < free_index_.size(); ++d)
    if (free_index_[d] >= 0) full[static_cast<Eigen::Index>(d)] += scale * free[free_index_[d]];
}

ElasticSystem::Deformation ElasticSystem::deformation(const Eigen::VectorXd& x) const {
  Deformation out;
  out.min_J.resize(mesh_.cell_count());
  out.energy_density.resize(mesh_.cell_count());
  std::visit(
      [&](const auto& m, const auto& rest) {
        using R = typename std::decay_t<decltype(rest)>::value_type;
        for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c) {
          const auto X = gather_nodes<R::nodes>(mesh_, c, x);
          double lo = std::numeric_limits<double>::infinity(), psi = 0.0, weight = 0.0;
          for (int q = 0; q < R::points; ++q) {
            const Mat3 F = X * rest[c].G[q];
            const double J = F.determinant();
            lo = std::min(lo, J);
            out.volume += rest[c].weight[q] * J;
            psi += rest[c].weight[q] * m.psi(F);
            weight += rest[c].weight[q];
          }
          out.min_J[c] = lo;
          out.energy_density[c] = psi / weight;
        }
      },
      material_, rest_);
  return out;
}

}  // namespace snh
