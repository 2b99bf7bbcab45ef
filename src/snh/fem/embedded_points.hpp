#pragma once
// Points embedded in a volume as contact terms see them (a flesh's render surface inside its lattice or tets):
// point i is p_i = Σ_k W(k, i) x_{I(k, i)}, k weights per point (8 trilinear, 4 barycentric; 1 for plain
// vertices). A term computes its energy's derivatives over a few points (a contact pair's 2 to 4, a collider's
// 1) and this class pulls them back to the volume by the chain rule: with J the points' weights (p = J x over
// the distinct volume vertices involved),
//     g_x = Jᵀ g_p,    H_x = Jᵀ H_p J,
// so a PSD H_p (projected first) gives a PSD H_x. The map is linear: a step dx moves the points by W dx
// exactly, which is what the terms' continuous collision detection runs on. A mesh's own surface is the case
// of one weight 1 per point (is_plain): every contact term takes its points this way, whether they are a
// volume's boundary vertices or a render surface embedded in it.
#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/contact/distance_core.hpp"
#include "snh/fem/term.hpp"
#include "snh/math/types.hpp"

namespace snh {

class EmbeddedPoints {
 public:
  EmbeddedPoints() = default;
  /// vertex, weight  k by #p (k ≥ 1; #p may be 0)
  /// volume_vertices #V, the ids' bound (a negative value: ids are only checked to be ≥ 0)
  /// Throws std::invalid_argument, one line starting with `who`, for shapes that differ, a non-finite weight
  /// or a vertex id out of range.
  EmbeddedPoints(Eigen::MatrixXi vertex, Eigen::MatrixXd weight, const std::string& who, Eigen::Index volume_vertices);
  /// Plain vertices: one weight 1 each.
  static EmbeddedPoints plain(const std::vector<int>& vertices, const std::string& who);
  /// Throws std::invalid_argument (one line, starting with `who`) for a volume vertex id at or beyond
  /// volume_vertices.
  void check_vertices(Eigen::Index volume_vertices, const std::string& who) const;
  /// Every vertex of a volume of n vertices as itself: point i is vertex i (a mesh's own surface).
  static EmbeddedPoints every(Eigen::Index n);

  /// True when each point is one vertex with weight exactly 1 (plain()/every()): the terms then gather and
  /// scatter coordinates directly, bit for bit, instead of through the weights.
  [[nodiscard]] bool is_plain() const;

  [[nodiscard]] Eigen::Index size() const { return vertex_.cols(); }
  [[nodiscard]] Eigen::Index arity() const { return vertex_.rows(); }
  [[nodiscard]] const Eigen::MatrixXi& vertex() const { return vertex_; }
  [[nodiscard]] const Eigen::MatrixXd& weight() const { return weight_; }
  /// These points only, in this order.
  [[nodiscard]] EmbeddedPoints select(const std::vector<int>& ids) const;

  /// Point i for positions x (or its motion for a step x). Throws std::logic_error for a vertex beyond x.
  [[nodiscard]] Vec3 point(const Eigen::VectorXd& x, Eigen::Index i) const;
  /// Every point, 3 by #p.
  [[nodiscard]] Eigen::Matrix3Xd points(const Eigen::VectorXd& x) const;

  /// Adds derivatives over N/3 points to the volume's gradient and Hessian (either may be null): slot s is
  /// point ids[s], or nothing where ids[s] < 0 (a collider's vertex, not a function of x: its rows are left
  /// out of J).
  template <int N>
  void scatter(const contact::Derivatives<N>& d, const std::array<int, 4>& ids, Eigen::VectorXd* gradient,
               const HessianValues* hessian) const;
  /// The volume vertices of the points ids[0 .. count) (negative ids skipped), sorted, each once.
  void volume_vertices(const std::array<int, 4>& ids, int count, std::vector<int>& out) const;
  /// Every pair of distinct volume vertices of those points, appended to a stencil's list (arity 2).
  void couple(const std::array<int, 4>& ids, int count, std::vector<int>& pairs) const;

 private:
  Eigen::MatrixXi vertex_;
  Eigen::MatrixXd weight_;
};

}  // namespace snh
