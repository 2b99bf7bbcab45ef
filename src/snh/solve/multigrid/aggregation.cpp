// Smoothed aggregation (the registry's "amg"; multigrid.hpp): the finest level's rigid-body modes, the
// aggregates of a level's nodes from its block graph, the tentative prolongator from the rigid-body modes,
// and the smoothed prolongator P = (I − ω D⁻¹ A) P_tent (its pattern once per pattern, its values for each
// matrix).
#include <algorithm>
#include <vector>

#include <Eigen/QR>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace multigrid {
namespace {

/// Every block of each row of F, both triangles (Level::full_start, full_node, full_slot).
void full_rows(Level& F) {
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
}

/// The aggregates of F's nodes (Level::aggregate); returns their number.
int greedy_aggregates(Level& F) {
  const int n = F.nodes;
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
  return count;
}

/// The level of F's `count` aggregates (its nodes, free DOFs and rigid-body modes), and F's tentative
/// prolongator.
Level tentative_prolongator(Level& F, int count) {
  const int n = F.nodes;
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
  return C;
}

/// F.down's pattern: the smoothed prolongator's (its values: smooth_prolongator()).
void smoothed_pattern(Level& F) {
  const int n = F.nodes;
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
}

}  // namespace

/// Level 0's rigid-body modes at rest (Level::near_null).
void rigid_body_modes(const VolumeMesh& mesh, Level& L) {
  // The rigid-body modes at rest: translations, and rotations about the centroid (for conditioning).
  const Eigen::Vector3d centre = L.nodes ? Eigen::Vector3d(mesh.vertices.rowwise().mean()) : Eigen::Vector3d::Zero();
  L.near_null.assign(18 * static_cast<std::size_t>(L.nodes), 0.0);
  for (int v = 0; v < L.nodes; ++v) {
    const Eigen::Vector3d p = mesh.vertices.col(v) - centre;
    Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> b(&L.near_null[18 * static_cast<std::size_t>(v)]);
    b.leftCols<3>().setIdentity();
    b.rightCols<3>() << 0.0, p.z(), -p.y(), -p.z(), 0.0, p.x(), p.y(), -p.x(), 0.0;  // columns e_a × p
  }
}

}  // namespace multigrid

using namespace multigrid;

/// Smoothed aggregation: appends the level of the aggregates of the last level's nodes, from its block
/// pattern (every connection counts as strong), with the tentative prolongator from the rigid-body modes
/// and the smoothed prolongator's pattern (values: smooth_prolongator()).
void MultigridPreconditioner::Impl::aggregate() {
  Level& F = levels.back();
  full_rows(F);
  const int count = greedy_aggregates(F);
  Level C = tentative_prolongator(F, count);
  smoothed_pattern(F);
  levels.push_back(std::move(C));
}

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

}  // namespace snh
