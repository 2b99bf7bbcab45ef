#include "snh/fem/elastic_term.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

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
  return mesh;
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
    const PointTerms t = point_terms(m, F, grad != nullptr, K != nullptr, p);  // one SVD at most
    psi += w * t.psi;
    if (grad) grad->noalias() += (w * t.P) * G.transpose();
    if (K) {
      // With vec(F)_{3j+i} = Σ_a x_{a,i} G_{a,j}: K_{(a,i),(b,k)} = w Σ_{j,l} G_{a,j} H_{3j+i,3l+k} G_{b,l}.
      const Mat9 H = w * t.H;
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

/// The cells of each material (every cell's index is below `materials`).
std::vector<std::vector<int>> cells_by_material(const std::vector<int>& material_of, std::size_t materials) {
  std::vector<std::vector<int>> out(materials);
  for (std::size_t c = 0; c < material_of.size(); ++c) {
    const int m = material_of[c];
    if (m < 0 || static_cast<std::size_t>(m) >= materials)
      throw std::invalid_argument(fmt::format("cell {}: material index {} (there are {} materials)", c, m, materials));
    out[m].push_back(static_cast<int>(c));
  }
  return out;
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
  if (!material_of_.empty()) {
    if (static_cast<Eigen::Index>(material_of_.size()) != mesh_.cell_count())
      throw std::invalid_argument(fmt::format("materials per cell: expected {}, got {}", mesh_.cell_count(), material_of_.size()));
    cells_of_ = cells_by_material(material_of_, materials_.size());
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
  Buckets by_colour = bucket(colours, [&](auto&& emit) {
    for (std::size_t c = 0; c < colour.size(); ++c) emit(colour[c], static_cast<int>(c));
  });
  colour_start_ = std::move(by_colour.start);
  colour_order_ = std::move(by_colour.items);
}

template <class Body>
void ElasticTerm::for_each_material(Body&& body) const {
  for (std::size_t k = 0; k < materials_.size(); ++k) {
    const int* list = cells_of_.empty() ? nullptr : cells_of_[k].data();
    const Eigen::Index count = cells_of_.empty() ? mesh_.cell_count() : static_cast<Eigen::Index>(cells_of_[k].size());
    std::visit([&](const auto& m, const auto& rest) { body(m, rest, list, count); }, materials_[k], rest_);
  }
}

void ElasticTerm::stencil(const Eigen::VectorXd&, Stencil& out) const {
  out.arity = nodes_per_cell(mesh_.type);
  out.vertices.assign(mesh_.cells.data(), mesh_.cells.data() + mesh_.cells.size());
}

std::vector<int> ElasticTerm::scatter_map(const HessianLayout& layout) const {
  // For each element and local pair (A, B), at B·ld + A (the column-major layout of the element
  // stiffness), the value index of (num(A), num(B)) when both are numbered and num(A) >= num(B);
  // −1 otherwise (the symmetric partner is stored instead).
  const int ld = 3 * nodes_per_cell(mesh_.type);
  const std::vector<int>& num = layout.numbering();
  std::vector<int> scatter(static_cast<std::size_t>(mesh_.cell_count()) * ld * ld, -1);
  for (Eigen::Index c = 0; c < mesh_.cell_count(); ++c)
    for (int A = 0; A < ld; ++A) {
      const int rA = num[3 * mesh_.cells(A / 3, c) + A % 3];
      if (rA < 0) continue;
      for (int B = 0; B < ld; ++B) {
        const int rB = num[3 * mesh_.cells(B / 3, c) + B % 3];
        if (rB < 0 || rA < rB) continue;
        const int e = layout.entry(rA, rB);
        if (e < 0) throw std::logic_error("elastic term: the layout does not hold an element's entries");
        scatter[(static_cast<std::size_t>(c) * ld + B) * ld + A] = e;
      }
    }
  return scatter;
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
  const Eigen::Index cells = mesh_.cell_count();
  std::vector<double> per(cells);
  if (!scatter) values = nullptr;
  std::visit(
      [&](const auto& rest_all) {
        using R = typename std::decay_t<decltype(rest_all)>::value_type;
        constexpr int N = R::nodes;
        constexpr int ld = 3 * N;
        // 1. Element terms, in one parallel loop per material, into per-element buffers (kept between
        //    calls: a fresh allocation of this size costs page faults every time).
        std::vector<double>& grads = grad_buffer_;
        std::vector<double>& stiff = stiffness_buffer_;
        if (gradient) grads.resize(static_cast<std::size_t>(cells) * ld);
        if (values) stiff.resize(static_cast<std::size_t>(cells) * ld * ld);
        for_each_material([&](const auto& m, const auto& rest, const int* list, Eigen::Index count) {
          if constexpr (std::is_same_v<std::decay_t<decltype(rest)>, std::decay_t<decltype(rest_all)>>) {
            ParallelErrors errors;
#pragma omp parallel for schedule(static) if (count * R::points >= parallel_threshold_)
            for (Eigen::Index i = 0; i < count; ++i) {
              errors.run(i, [&] {
                const Eigen::Index c = list ? list[i] : i;
                Eigen::Matrix<double, ld, ld> K;
                Eigen::Matrix<double, 3, N> gc;
                per[c] = element_terms(m, rest[c], gather_nodes<N>(mesh_, c, x), gradient ? &gc : nullptr,
                                       values ? &K : nullptr, projection);
                if (gradient) Eigen::Map<Eigen::Matrix<double, 3, N>>(grads.data() + static_cast<std::size_t>(c) * ld) = gc;
                if (values) Eigen::Map<Eigen::Matrix<double, ld, ld>>(stiff.data() + static_cast<std::size_t>(c) * ld * ld) = K;
              });
            }
            errors.rethrow();
          }
        });
        // 2. Scatter, colour by colour: elements of one colour share no vertex, so no two threads touch
        //    the same entry, and each entry receives its terms in colour order for any thread count.
        if (!gradient && !values) return;
        for (int k = 0; k + 1 < static_cast<int>(colour_start_.size()); ++k) {
          const int begin = colour_start_[k], end = colour_start_[k + 1];
          ParallelErrors errors;
#pragma omp parallel for schedule(static) if ((end - begin) * N >= parallel_threshold_)
          for (int i = begin; i < end; ++i) {
            errors.run(i, [&] {
              const int c = colour_order_[i];
              if (gradient) {
                const double* g = grads.data() + static_cast<std::size_t>(c) * ld;
                for (int a = 0; a < N; ++a)
                  gradient->segment<3>(3 * mesh_.cells(a, c)) += Eigen::Map<const Eigen::Vector3d>(g + 3 * a);
              }
              if (values) {
                const int* map = scatter->data() + static_cast<std::size_t>(c) * ld * ld;
                const double* K = stiff.data() + static_cast<std::size_t>(c) * ld * ld;  // same layout as map
                for (int e = 0; e < ld * ld; ++e)
                  if (map[e] >= 0) values[map[e]] += K[e];
              }
            });
          }
          errors.rethrow();
        }
      },
      rest_);
  double total = 0.0;
  for (double e : per) total += e;  // fixed order: deterministic
  return total;
}

ElasticTerm::Deformation ElasticTerm::deformation(const Eigen::VectorXd& x) const {
  Deformation out;
  out.min_J.resize(mesh_.cell_count());
  out.energy_density.resize(mesh_.cell_count());
  for_each_material([&](const auto& m, const auto& rest, const int* list, Eigen::Index count) {
    using R = typename std::decay_t<decltype(rest)>::value_type;
    for (Eigen::Index i = 0; i < count; ++i) {
      const Eigen::Index c = list ? list[i] : i;
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
  });
  return out;
}

}  // namespace snh
