#pragma once
// Which degrees of freedom Newton solves for (docs/design.md): every vertex has three DOFs (x y z, DOF
// 3v + k); a DOF is free (an unknown) or kinematic (its value is prescribed: pins, bones). Free DOFs are
// numbered in increasing DOF order; vectors "on the free DOFs" use that numbering.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace snh {

class DofMap {
 public:
  DofMap() = default;
  /// kinematic  one flag per DOF (3 #V): true where the DOF's value is prescribed
  explicit DofMap(const std::vector<std::uint8_t>& kinematic);

  [[nodiscard]] Eigen::Index dofs() const { return static_cast<Eigen::Index>(free_index_.size()); }
  [[nodiscard]] Eigen::Index free_count() const { return free_count_; }
  /// Free index of each DOF, −1 where kinematic.
  [[nodiscard]] const std::vector<int>& free_index() const { return free_index_; }
  [[nodiscard]] bool is_free(Eigen::Index dof) const { return free_index_[static_cast<std::size_t>(dof)] >= 0; }

  /// The free entries of a full DOF vector (3 #V → free_count()).
  [[nodiscard]] Eigen::VectorXd gather_free(const Eigen::VectorXd& full) const;
  /// full[d] += scale · free[free index of d] for every free DOF d.
  void scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const;
  /// A full DOF vector holding `free` on the free DOFs and 0 on the kinematic ones.
  [[nodiscard]] Eigen::VectorXd expand(const Eigen::VectorXd& free) const;

 private:
  std::vector<int> free_index_;
  Eigen::Index free_count_ = 0;
};

}  // namespace snh
