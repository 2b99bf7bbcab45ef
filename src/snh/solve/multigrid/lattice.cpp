// Lattice coarsening (the registry's "mg"; multigrid.hpp): the integer lattice coordinates of a hex mesh's
// vertices, the finest level's lattice, and each coarser level of twice the cell size with the trilinear
// prolongation from it.
#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace multigrid {
namespace {

/// Offset of hex corner k from corner 0 in lattice units (VolumeMesh's corner order).
Eigen::Vector3i corner_offset(int k) { return {k & 1, (k >> 1) & 1, (k >> 2) & 1}; }

}  // namespace
}  // namespace multigrid

using multigrid::corner_offset;

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

/// Level 0's lattice (coordinates, pieces, cells) for a hex mesh from its lattice_coordinates().
void multigrid::lattice_level(const VolumeMesh& mesh, const LatticeCoordinates& lattice, Level& L) {
  L.at.resize(L.nodes);
  L.piece = lattice.piece;
  for (int v = 0; v < L.nodes; ++v) L.at[v] = lattice.coordinates.col(v);
  L.cells.resize(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (int k = 0; k < 8; ++k) L.cells[c][k] = mesh.cells(k, c);
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

}  // namespace snh
