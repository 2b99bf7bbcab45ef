#pragma once
// The sparsity pattern of a symmetric matrix over numbered DOFs (docs/design.md): the lower triangle in
// compressed columns, every column starting with its diagonal entry (the form CHOLMOD takes), built from
// stencils, groups of vertices whose DOFs are all coupled (an element's nodes, a contact pair's vertices).
// Energy terms add their Hessian entries into values laid out this way (HessianValues); a term with a
// fixed stencil precomputes where each entry goes (a scatter map) whenever the layout is rebuilt.
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "snh/math/types.hpp"
#include "snh/math/sparse.hpp"

namespace snh {

/// Groups of `arity` vertices, each group fully coupled; `vertices` holds the groups one after another.
struct Stencil {
  int arity = 0;
  std::vector<int> vertices;
  [[nodiscard]] Eigen::Index groups() const {
    return arity > 0 ? static_cast<Eigen::Index>(vertices.size()) / arity : 0;
  }
};

class HessianLayout {
 public:
  HessianLayout() = default;
  /// numbering  per DOF (3 #V), its row and column in the matrix, −1 to leave the DOF out; the numbers
  ///            used must be 0 … size−1, each once
  /// size       rows (= columns) of the matrix
  /// stencils   the couplings; every numbered DOF also gets its diagonal entry
  HessianLayout(std::vector<int> numbering, int size, const std::vector<const Stencil*>& stencils);
  // Moves swap the pattern: Eigen 3.4's SparseMatrix has no move operations of its own, so a defaulted move
  // copied every entry (0.15 s for Figure 1's layout, at each rebuild).
  HessianLayout(const HessianLayout&) = default;
  HessianLayout& operator=(const HessianLayout&) = default;
  HessianLayout(HessianLayout&& other) noexcept { swap(other); }
  HessianLayout& operator=(HessianLayout&& other) noexcept {
    HessianLayout taken;
    taken.swap(other);
    swap(taken);
    return *this;
  }
  ~HessianLayout() = default;
  void swap(HessianLayout& other) noexcept {
    numbering_.swap(other.numbering_);
    pattern_.swap(other.pattern_);
    neighbour_start_.swap(other.neighbour_start_);
    neighbours_.swap(other.neighbours_);
    std::swap(id_, other.id_);
  }

  /// The pattern, values zero.
  [[nodiscard]] const SparseLower& pattern() const { return pattern_; }
  [[nodiscard]] const std::vector<int>& numbering() const { return numbering_; }
  [[nodiscard]] int size() const { return static_cast<int>(pattern_.rows()); }
  /// The value index of (row, col), row ≥ col; −1 where the pattern has no such entry.
  [[nodiscard]] int entry(int row, int col) const;
  /// True when every pair of vertices coupled by `stencil` is coupled here.
  [[nodiscard]] bool covers(const Stencil& stencil) const;
  /// Different for every layout built (0 for an empty one): tells a matrix that holds an older pattern.
  [[nodiscard]] std::uint64_t id() const { return id_; }

 private:
  std::vector<int> numbering_;
  SparseLower pattern_;
  std::vector<int> neighbour_start_, neighbours_;  ///< per vertex, the sorted vertices it is coupled with
  std::uint64_t id_ = 0;
};

/// The values of a matrix in a layout, to which terms add their entries.
class HessianValues {
 public:
  HessianValues(const HessianLayout& layout, double* values) : layout_(&layout), values_(values) {}
  [[nodiscard]] const HessianLayout& layout() const { return *layout_; }
  [[nodiscard]] double* values() const { return values_; }
  /// Adds the 3x3 block ∂²E/∂x_a∂x_b (rows: DOFs of vertex a, columns: vertex b); for a ≠ b the
  /// symmetric block (b, a) is implied, so add each unordered pair once. DOFs outside the numbering are
  /// skipped. Throws std::logic_error if the layout does not couple a and b.
  void add_block(int a, int b, const Mat3& block) const;

 private:
  const HessianLayout* layout_;
  double* values_;
};

}  // namespace snh
