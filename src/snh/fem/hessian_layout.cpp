#include "snh/fem/hessian_layout.hpp"

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/fem/buckets.hpp"

namespace snh {
namespace {

std::atomic<std::uint64_t> next_layout_id{1};

}  // namespace

HessianLayout::HessianLayout(std::vector<int> numbering, int size, const std::vector<const Stencil*>& stencils)
    : numbering_(std::move(numbering)), id_(next_layout_id++) {
  const Eigen::Index vertices = static_cast<Eigen::Index>(numbering_.size()) / 3;
  // Every group of every stencil, and vertex -> the groups it is in.
  std::vector<std::pair<const Stencil*, int>> groups;  // (stencil, index of the group's first vertex)
  for (const Stencil* s : stencils)
    for (Eigen::Index g = 0; g < s->groups(); ++g) groups.emplace_back(s, static_cast<int>(g * s->arity));
  const Buckets vertex_groups = bucket(static_cast<int>(vertices), [&](auto&& emit) {
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (int k = 0; k < groups[g].first->arity; ++k) emit(groups[g].first->vertices[groups[g].second + k], static_cast<int>(g));
  });
  // Vertex neighbours: every vertex sharing a group with it, and itself; sorted.
  neighbour_start_.assign(vertices + 1, 0);
  std::vector<int> list;
  for (Eigen::Index v = 0; v < vertices; ++v) {
    list.clear();
    list.push_back(static_cast<int>(v));
    for (int i = vertex_groups.start[v]; i < vertex_groups.start[v + 1]; ++i) {
      const auto& [s, first] = groups[vertex_groups.items[i]];
      list.insert(list.end(), s->vertices.begin() + first, s->vertices.begin() + first + s->arity);
    }
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    neighbours_.insert(neighbours_.end(), list.begin(), list.end());
    neighbour_start_[v + 1] = static_cast<int>(neighbours_.size());
  }

  // Columns in numbering order; column c (DOF d) holds the numbered DOFs of d's neighbours with number >= c.
  std::vector<int> dof_of(size, -1);
  for (std::size_t d = 0; d < numbering_.size(); ++d) {
    const int c = numbering_[d];
    if (c < 0) continue;
    if (c >= size || dof_of[c] >= 0) throw std::invalid_argument(fmt::format("layout numbering: {} used twice or out of range", c));
    dof_of[c] = static_cast<int>(d);
  }
  std::vector<int> outer(size + 1, 0), inner;
  for (int c = 0; c < size; ++c) {
    if (dof_of[c] < 0) throw std::invalid_argument(fmt::format("layout numbering: {} is not used", c));
    const int v = dof_of[c] / 3;
    const std::size_t first = inner.size();
    for (int i = neighbour_start_[v]; i < neighbour_start_[v + 1]; ++i)
      for (int l = 0; l < 3; ++l) {
        const int row = numbering_[3 * static_cast<std::size_t>(neighbours_[i]) + l];
        if (row >= c) inner.push_back(row);
      }
    std::sort(inner.begin() + static_cast<std::ptrdiff_t>(first), inner.end());  // already sorted for increasing numberings
    outer[c + 1] = static_cast<int>(inner.size());
  }
  std::vector<double> zeros(inner.size(), 0.0);
  pattern_ = Eigen::Map<const SparseLower>(size, size, static_cast<Eigen::Index>(inner.size()), outer.data(), inner.data(),
                                           zeros.data());
  pattern_.makeCompressed();
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
