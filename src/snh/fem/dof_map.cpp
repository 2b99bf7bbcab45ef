#include "snh/fem/dof_map.hpp"

namespace snh {

DofMap::DofMap(const std::vector<std::uint8_t>& kinematic) : free_index_(kinematic.size(), -1) {
  for (std::size_t d = 0; d < kinematic.size(); ++d)
    if (!kinematic[d]) free_index_[d] = static_cast<int>(free_count_++);
}

Eigen::VectorXd DofMap::gather_free(const Eigen::VectorXd& full) const {
  Eigen::VectorXd out(free_count_);
  for (std::size_t d = 0; d < free_index_.size(); ++d)
    if (free_index_[d] >= 0) out[free_index_[d]] = full[static_cast<Eigen::Index>(d)];
  return out;
}

void DofMap::scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const {
  for (std::size_t d = 0; d < free_index_.size(); ++d)
    if (free_index_[d] >= 0) full[static_cast<Eigen::Index>(d)] += scale * free[free_index_[d]];
}

Eigen::VectorXd DofMap::expand(const Eigen::VectorXd& free) const {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(dofs());
  for (std::size_t d = 0; d < free_index_.size(); ++d)
    if (free_index_[d] >= 0) full[static_cast<Eigen::Index>(d)] = free[free_index_[d]];
  return full;
}

}  // namespace snh
