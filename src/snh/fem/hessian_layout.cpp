#include "snh/fem/hessian_layout.hpp"

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <utility>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/fem/buckets.hpp"

namespace snh {
namespace {

std::atomic<std::uint64_t> next_layout_id{1};

/// Layouts of this many vertices and more are built on all threads.
constexpr int kParallelVertices = 4096;

}  // namespace

HessianLayout::HessianLayout(std::vector<int> numbering, int size, const std::vector<const Stencil*>& stencils)
    : numbering_(std::move(numbering)), id_(next_layout_id++) {
  const int vertices = static_cast<int>(numbering_.size() / 3);
  // Every group of every stencil, and vertex -> the groups it is in.
  std::vector<std::pair<const Stencil*, int>> groups;  // (stencil, index of the group's first vertex)
  for (const Stencil* s : stencils)
    for (Eigen::Index g = 0; g < s->groups(); ++g) groups.emplace_back(s, static_cast<int>(g * s->arity));
  const Buckets vertex_groups = bucket(vertices, [&](auto&& emit) {
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (int k = 0; k < groups[g].first->arity; ++k) emit(groups[g].first->vertices[groups[g].second + k], static_cast<int>(g));
  });
  // Columns in numbering order; column c (DOF d) will hold the numbered DOFs of d's neighbours with number >= c.
  std::vector<int> dof_of(static_cast<std::size_t>(size), -1);
  for (std::size_t d = 0; d < numbering_.size(); ++d) {
    const int c = numbering_[d];
    if (c < 0) continue;
    if (c >= size || dof_of[static_cast<std::size_t>(c)] >= 0)
      throw std::invalid_argument(fmt::format("layout numbering: {} used twice or out of range", c));
    dof_of[static_cast<std::size_t>(c)] = static_cast<int>(d);
  }
  for (int c = 0; c < size; ++c)
    if (dof_of[static_cast<std::size_t>(c)] < 0) throw std::invalid_argument(fmt::format("layout numbering: {} is not used", c));

  // Everything is allocated before the parallel loops below, whose bodies neither allocate nor throw; each
  // vertex's and each column's entries are made by one thread, in the same order for any thread count.
  const bool parallel = vertices >= kParallelVertices;
  // Vertex neighbours: every vertex sharing a group with it, and itself; sorted. Each vertex's list is made
  // in a slot as long as its groups' vertices together, then packed.
  std::vector<std::int64_t> slot(static_cast<std::size_t>(vertices) + 1, 0);
  for (int v = 0; v < vertices; ++v) {
    std::int64_t length = 1;
    for (int i = vertex_groups.start[v]; i < vertex_groups.start[v + 1]; ++i) length += groups[vertex_groups.items[i]].first->arity;
    slot[v + 1] = slot[v] + length;
  }
  std::vector<int> scratch(static_cast<std::size_t>(slot[vertices]));
  neighbour_start_.assign(static_cast<std::size_t>(vertices) + 1, 0);
#pragma omp parallel for schedule(dynamic, 1024) if (parallel)
  for (int v = 0; v < vertices; ++v) {
    int* const first = scratch.data() + slot[v];
    int* last = first;
    *last++ = v;
    for (int i = vertex_groups.start[v]; i < vertex_groups.start[v + 1]; ++i) {
      const auto& [s, at] = groups[vertex_groups.items[i]];
      last = std::copy(s->vertices.begin() + at, s->vertices.begin() + at + s->arity, last);
    }
    std::sort(first, last);
    neighbour_start_[v + 1] = static_cast<int>(std::unique(first, last) - first);
  }
  for (int v = 0; v < vertices; ++v) neighbour_start_[v + 1] += neighbour_start_[v];
  neighbours_.resize(static_cast<std::size_t>(neighbour_start_[vertices]));
#pragma omp parallel for schedule(static) if (parallel)
  for (int v = 0; v < vertices; ++v)
    std::copy(scratch.begin() + slot[v], scratch.begin() + slot[v] + (neighbour_start_[v + 1] - neighbour_start_[v]),
              neighbours_.begin() + neighbour_start_[v]);
  scratch = {};

  // The columns: their lengths, then their rows, written straight into the matrix (values zero).
  const auto for_each_row = [&](int c, auto&& take) {
    const int v = dof_of[static_cast<std::size_t>(c)] / 3;
    for (int i = neighbour_start_[v]; i < neighbour_start_[v + 1]; ++i)
      for (int l = 0; l < 3; ++l) {
        const int row = numbering_[3 * static_cast<std::size_t>(neighbours_[i]) + l];
        if (row >= c) take(row);
      }
  };
  pattern_.resize(size, size);
  int* const outer = pattern_.outerIndexPtr();
  outer[0] = 0;
#pragma omp parallel for schedule(static) if (parallel)
  for (int c = 0; c < size; ++c) {
    int n = 0;
    for_each_row(c, [&n](int) { ++n; });
    outer[c + 1] = n;
  }
  for (int c = 0; c < size; ++c) outer[c + 1] += outer[c];
  pattern_.resizeNonZeros(outer[size]);
  int* const inner = pattern_.innerIndexPtr();
  double* const values = pattern_.valuePtr();
#pragma omp parallel for schedule(static) if (parallel)
  for (int c = 0; c < size; ++c) {
    int* const first = inner + outer[c];
    int* next = first;
    for_each_row(c, [&next](int row) { *next++ = row; });
    if (!std::is_sorted(first, next)) std::sort(first, next);  // already sorted for increasing numberings
    std::fill(values + outer[c], values + outer[c + 1], 0.0);
  }
}

int HessianLayout::entry(int row, int col) const {
  const int* in = pattern_.innerIndexPtr();
  const int* first = in + pattern_.outerIndexPtr()[col];
  const int* last = in + pattern_.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(first, last, row);
  return it != last && *it == row ? static_cast<int>(it - in) : -1;
}

bool HessianLayout::covers(const Stencil& stencil) const {
  for (Eigen::Index g = 0; g < stencil.groups(); ++g)
    for (int i = 0; i < stencil.arity; ++i) {
      const int a = stencil.vertices[g * stencil.arity + i];
      if (a < 0 || a + 1 >= static_cast<int>(neighbour_start_.size())) return false;
      const auto first = neighbours_.begin() + neighbour_start_[a], last = neighbours_.begin() + neighbour_start_[a + 1];
      for (int j = i + 1; j < stencil.arity; ++j)
        if (!std::binary_search(first, last, stencil.vertices[g * stencil.arity + j])) return false;
    }
  return true;
}

void HessianValues::add_block(int a, int b, const Mat3& block) const {
  const std::vector<int>& num = layout_->numbering();
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const int r = num[3 * static_cast<std::size_t>(a) + i], c = num[3 * static_cast<std::size_t>(b) + k];
      if (r < 0 || c < 0) continue;
      if (a == b && r < c) continue;  // the diagonal block is symmetric: its lower half only
      const int e = layout_->entry(std::max(r, c), std::min(r, c));
      if (e < 0) throw std::logic_error(fmt::format("Hessian layout does not couple vertices {} and {}", a, b));
      values_[e] += block(i, k);
    }
}

}  // namespace snh
