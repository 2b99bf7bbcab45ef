#pragma once
// Soft attachments (docs/design.md): zero-rest-length springs pulling chosen vertices toward targets that
// may move with time, E = ½ Σ_i k_i |x_i − t_i|². A soft bone binding is one (the flesh in a shell around
// a bone's capsule pulled toward where the bone carries it); an animator's attachment is another. The
// Hessian is k_i I on each vertex's own DOFs, so the term adds no coupling to the layout.
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "snh/fem/term.hpp"

namespace snh {

class AttachmentTerm final : public Term {
 public:
  /// Fills `out` (3 by #vertices) with the targets at time t.
  using Targets = std::function<void(double t, Eigen::Matrix3Xd& out)>;
  /// vertices   the attached vertices (each once)
  /// stiffness  k_i ≥ 0 per attached vertex (force per unit distance)
  /// targets    where they are pulled at time t; asked once here (t = 0) and at every at_time()
  /// Throws std::invalid_argument (one line) for sizes that do not match, a repeated or negative vertex
  /// index, or a stiffness that is negative or not finite.
  AttachmentTerm(std::vector<int> vertices, Eigen::VectorXd stiffness, Targets targets);

  [[nodiscard]] std::string_view name() const override { return "attachment"; }
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  void at_time(double t) override;

  [[nodiscard]] const std::vector<int>& vertices() const { return vertices_; }
  [[nodiscard]] const Eigen::VectorXd& stiffness() const { return stiffness_; }
  /// The targets of the last at_time() (3 by #vertices).
  [[nodiscard]] const Eigen::Matrix3Xd& targets() const { return current_; }

 private:
  std::vector<int> vertices_;
  Eigen::VectorXd stiffness_;
  Targets targets_;
  Eigen::Matrix3Xd current_;
};

}  // namespace snh
