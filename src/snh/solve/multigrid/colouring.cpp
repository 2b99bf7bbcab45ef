// The smoother's colouring (multigrid.hpp): each level's colours, its block rows in sweep order with their
// blocks of lower colours first, and the row chunks of the product A x. All from the level's pattern alone,
// never from the thread count, so that results are the same for any thread count.
#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "snh/solve/multigrid/levels.hpp"

namespace snh::multigrid {

/// The smoother's colours and block rows of L (see Level), from its pattern. Lattice levels: the parity of the
/// node's lattice coordinates (8 colours), which 27-point stencils and their trilinear Galerkin products keep
/// valid (no block couples two nodes of one parity); a node whose block row couples it to a lower node of its
/// own parity (contact) is coloured greedily instead, from colour 8 on. Aggregation levels: greedy colouring in
/// node order (each node the smallest colour none of its neighbours coloured before it has). A lexicographic
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
  // Parity where the level has lattice coordinates; a node coupled to a lower node of its own parity (a contact
  // pair's coupling across the lattice) is moved out of the parity colours, so that one pair changes the
  // colours of its own few nodes only, not the sweep order of the whole level.
  L.colour.assign(n, -1);
  if (!L.at.empty()) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3i& a = L.at[i];
      L.colour[i] = (a.x() & 1) | (a.y() & 1) << 1 | (a.z() & 1) << 2;
    }
    for (int i = 0; i < n; ++i)
      for (int s = L.A.start[i]; s + 1 < L.A.start[i + 1]; ++s)
        if (L.colour[L.A.col[s]] == L.colour[i]) {
          L.colour[i] = -1;
          break;
        }
  }
  // The rest (every node of an aggregation level), greedily in node order: the smallest colour, from the first
  // after the parity ones, that no neighbour has.
  const int first_free = L.at.empty() ? 0 : 8;
  std::vector<int> seen;  // seen[c] == i + 1: colour c is taken by a neighbour of i
  for (int i = 0; i < n; ++i) {
    if (L.colour[i] >= 0) continue;
    for (int e = L.row_start[i]; e < L.row_start[i + 1]; ++e) {
      const int c = L.colour[L.row_node[e]];
      if (c < 0) continue;
      if (c >= static_cast<int>(seen.size())) seen.resize(c + 1, 0);
      seen[c] = i + 1;
    }
    int c = first_free;
    while (c < static_cast<int>(seen.size()) && seen[c] == i + 1) ++c;
    L.colour[i] = c;
  }
  const int colours = n ? *std::max_element(L.colour.begin(), L.colour.end()) + 1 : 0;
  L.colour_start.assign(colours + 1, 0);
  for (int i = 0; i < n; ++i) ++L.colour_start[L.colour[i] + 1];
  for (int c = 0; c < colours; ++c) L.colour_start[c + 1] += L.colour_start[c];
  L.colour_phase.assign(1, 0);
  for (int c = 0; c < colours; ++c) {
    if (c > 0 && L.small_colour(c) && L.small_colour(c - 1)) L.colour_phase.back() = c + 1;  // the run of small colours goes on
    else L.colour_phase.push_back(c + 1);
  }
  L.by_colour.resize(n);
  {
    std::vector<int> next(L.colour_start.begin(), L.colour_start.end() - 1);
    for (int i = 0; i < n; ++i) L.by_colour[next[L.colour[i]]++] = i;
  }
  // The rows in sweep order, so that each sweep reads them front to back as one stream (in node order a
  // colour's rows lie every eighth row apart, and a sweep would skip through memory).
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

}  // namespace snh::multigrid
