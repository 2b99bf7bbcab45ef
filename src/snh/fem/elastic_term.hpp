#pragma once
// Total elastic energy of a mesh, its gradient, and the PSD-projected Hessian restricted to the free
// degrees of freedom, assembled in parallel into a fixed sparse pattern through a precomputed scatter
// map (DESIGN.md fem/). Elements are coloured so that no two elements of a colour share a vertex: the
// colours run in sequence and each colour in parallel, so every sum is taken in the same order for any
// thread count (bit-identical results).
#include <cstdint>
#include <vector>

#include <Eigen/Dense>
#include <Eigen/SparseCore>

#include "snh/fem/objective.hpp"
#include "snh/fem/rest_state.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

class ElasticSystem final : public Objective {
 public:
  /// mesh      the rest mesh (copied)
  /// material  the energy density (copied)
  /// fixed     one flag per DOF (3 #V, x y z per vertex): true where the DOF is kinematic
  ElasticSystem(VolumeMesh mesh, AnyMaterial material, std::vector<std::uint8_t> fixed);

  /// Total energy Σ_e Σ_q w_q ψ(F_q); +∞ if any element is outside its energy's domain.
  ///   x  deformed positions, 3 #V (x y z per vertex)
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;

  /// Energy, gradient on the free DOFs and (optionally) the projected Hessian on the free DOFs.
  /// Uses internal buffers: do not call evaluate() concurrently on the same system.
  ///   gradient  resized to free_count(); entries of fixed DOFs are left out
  ///   hessian   nullptr to skip; otherwise overwritten in the fixed pattern (pattern() layout)
  /// Returns the energy (+∞ if undefined anywhere; gradient and Hessian are then not meaningful).
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, SparseLower* hessian,
                  PsdProjection projection = PsdProjection::clamp) const override;

  /// An empty matrix with the fixed sparsity pattern of the free-DOF Hessian.
  [[nodiscard]] const SparseLower& pattern() const override { return pattern_; }

  [[nodiscard]] Eigen::Index free_count() const { return free_count_; }
  /// Free index of each DOF, −1 where fixed.
  [[nodiscard]] const std::vector<int>& free_index() const { return free_index_; }
  [[nodiscard]] const VolumeMesh& mesh() const { return mesh_; }
  [[nodiscard]] const AnyMaterial& material() const { return material_; }
  [[nodiscard]] const RestState& rest() const { return rest_; }
  [[nodiscard]] int colour_count() const { return static_cast<int>(colour_start_.size()) - 1; }

  /// Gathers the free entries of a full DOF vector.
  [[nodiscard]] Eigen::VectorXd gather_free(const Eigen::VectorXd& full) const;
  /// Adds a free-DOF vector into a full DOF vector: full[d] += scale · free[free_index[d]].
  void scatter_add_free(const Eigen::VectorXd& free, double scale, Eigen::VectorXd& full) const override;

  /// Loops with less work than this many quadrature points (element loops; scatters count one per
  /// node) run on one thread: for small meshes waking threads (and, when other processes compete for
  /// the cores, waiting at barriers) costs more than the work. Default 2048; 0 makes every loop parallel.
  void set_parallel_threshold(Eigen::Index t) { parallel_threshold_ = t; }

  /// det F and ψ at every quadrature point, in one pass: each element's minimum det F and mean energy
  /// density, and the deformed volume.
  struct Deformation {
    Eigen::VectorXd min_J;           ///< per element, the smallest det F over its quadrature points
    Eigen::VectorXd energy_density;  ///< per element, Σ_q w_q ψ(F_q) / Σ_q w_q (+∞ where ψ is undefined)
    double volume = 0.0;             ///< Σ_e Σ_q w_q det F_q (signed)
  };
  [[nodiscard]] Deformation deformation(const Eigen::VectorXd& x) const;

 private:
  VolumeMesh mesh_;
  AnyMaterial material_;
  RestState rest_;
  std::vector<int> free_index_;
  Eigen::Index free_count_ = 0;
  SparseLower pattern_;
  std::vector<int> scatter_;        ///< per element, (3N)² value indices into pattern_ (column-major), −1 to skip
  std::vector<int> colour_order_;   ///< element ids grouped by colour
  std::vector<int> colour_start_;   ///< colour c owns colour_order_[colour_start_[c] .. colour_start_[c+1])
  Eigen::Index parallel_threshold_ = 2048;
  // Per-element gradient and stiffness buffers reused by evaluate() (not thread-safe across calls).
  mutable std::vector<double> grad_buffer_, stiffness_buffer_;
};

}  // namespace snh
