#pragma once
// The elastic energy of a mesh as a Term (docs/design.md): Σ_e Σ_q w_q ψ(F_q), its gradient, and its
// (per-element PSD-projected) Hessian, assembled in parallel through a scatter map precomputed for each
// Hessian layout (an element's stiffness is computed and scattered once per pair of DOFs: it is symmetric).
// Elements are coloured, in chunks of consecutive cells where that needs few colours (a lattice's slabs) or
// one by one, so that no two units of a colour share a vertex: the colours run in sequence and each colour's
// units in parallel, each unit's cells in order, each element adding its terms straight into the results, so
// every sum is taken in the same order for any thread count (bit-identical results). Each cell may have its own material (the runtime choice is one std::visit
// per material, outside the element loop) and its own weight scale (the fraction of an embedding lattice's
// cell that the solid fills).
#include <vector>

#include <Eigen/Dense>

#include "snh/fem/rest_state.hpp"
#include "snh/fem/term.hpp"
#include "snh/material/fibre.hpp"
#include "snh/material/registry.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// A muscle cell's fibres: the direction a (unit, rest frame), their energy (added to the cell's material)
/// and the active strain (the cell's energies act on F F_a⁻¹): material/fibre.hpp.
struct CellFibre {
  Vec3 direction = Vec3::UnitX();
  FibreEnergy energy;
  ActiveStrain active;
};

class ElasticTerm final : public Term {
 public:
  /// mesh      the rest mesh (copied)
  /// material  the energy density of every cell
  ElasticTerm(VolumeMesh mesh, AnyMaterial material);
  /// materials         the energies used
  /// material_of_cell  #C indices into materials (empty: every cell uses materials[0])
  /// weight_scale      #C factors > 0 on each cell's quadrature weights (empty: all 1)
  ElasticTerm(VolumeMesh mesh, std::vector<AnyMaterial> materials, std::vector<int> material_of_cell,
              Eigen::VectorXd weight_scale = {});

  [[nodiscard]] std::string_view name() const override { return "elastic"; }
  /// Σ_e Σ_q w_q ψ(F_q); +∞ if any element is outside its energy's domain.
  [[nodiscard]] double energy(const Eigen::VectorXd& x) const override;
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                  PsdProjection projection) const override;
  /// The cells.
  void stencil(const Eigen::VectorXd& x, Stencil& out) const override;
  /// The new map is written over the old one: a layout rebuilt for contact pairs then reuses its memory
  /// instead of touching 70 MB of fresh pages at Figure 1's size (0.2 s here).
  void bind(const HessianLayout& layout) override { scatter_map(layout, scatter_); }

  /// Per element, 6 N² value indices into `layout`'s values, one per entry of the element stiffness's N by N
  /// blocks K_ik (the DOFs 3a+i and 3b+k, i >= k); −1 to skip (a DOF the layout leaves out, or a pair that
  /// K_ii holds twice).
  [[nodiscard]] std::vector<int> scatter_map(const HessianLayout& layout) const {
    std::vector<int> scatter;
    scatter_map(layout, scatter);
    return scatter;
  }
  /// The same into `scatter` (resized; every entry written).
  void scatter_map(const HessianLayout& layout, std::vector<int>& scatter) const;
  /// Adds the Hessian at x to `values` through a scatter map of scatter_map() (another layout than the
  /// bound one: a damping matrix over every DOF).
  void add_hessian(const Eigen::VectorXd& x, const std::vector<int>& scatter, double* values, PsdProjection projection) const;

  [[nodiscard]] const VolumeMesh& mesh() const { return mesh_; }
  /// The rest data of every cell (a copy, one record per cell).
  [[nodiscard]] RestState rest() const;
  /// Each cell's rest volume (Σ_q weight).
  [[nodiscard]] Eigen::VectorXd rest_volumes() const;
  /// Cells whose rest data agree to a relative 2^-40 or better (a lattice's congruent cells, equal but for
  /// the rounding of their coordinates) share one record (on: the default; a lattice then keeps one record
  /// instead of one per cell, which every energy, gradient and Hessian would stream). Off: one per cell.
  void share_rest(bool on);
  /// The rest records kept.
  [[nodiscard]] int rest_records() const;
  /// Muscle cells: fibre_of_cell (#C indices into fibres, −1 for a cell without; empty: none). A muscle
  /// cell's energy at each point is ψ(F A) + ψ_fibre(F A; a), A = F_a⁻¹ (docs/math.md §14). Without fibres
  /// every value is bit-identical to a term that never had any. Throws std::invalid_argument (one line) for
  /// an index out of range or a count that is not #C.
  void set_fibres(std::vector<int> fibre_of_cell, std::vector<CellFibre> fibres);
  /// The active strain of fibre set f (a muscle's activation changing over time).
  void set_active_strain(int f, const ActiveStrain& active);
  [[nodiscard]] const std::vector<CellFibre>& fibres() const { return fibres_; }
  /// The fibres of cell c, or null.
  [[nodiscard]] const CellFibre* fibre(Eigen::Index c) const {
    if (fibre_of_.empty()) return nullptr;
    const int f = fibre_of_[static_cast<std::size_t>(c)];
    return f < 0 ? nullptr : &fibres_[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] const std::vector<AnyMaterial>& materials() const { return materials_; }
  /// The material of cell c.
  [[nodiscard]] const AnyMaterial& material(Eigen::Index c) const {
    return materials_[material_of_.empty() ? 0 : material_of_[static_cast<std::size_t>(c)]];
  }
  [[nodiscard]] int colour_count() const {
    return static_cast<int>((group_start_.size() - 1) / materials_.size());
  }
  /// The units that are coloured: chunks of this many consecutive cells, each run by one thread in cell order
  /// (where they need at most kMaxChunkColours colours: a lattice's cells in grid order make slabs), or
  /// single cells (1). set_chunk_cells(−1) picks max(1024, cells / 64), as the constructor does; 0 or 1
  /// colours single cells. Either way each sum is taken in an order that does not depend on the thread count.
  void set_chunk_cells(Eigen::Index chunk);
  [[nodiscard]] Eigen::Index chunk_cells() const { return chunk_cells_; }
  static constexpr int kMaxChunkColours = 4;
  static constexpr int kCellsPerPiece = 32;  ///< single-cell colouring: cells per unit of parallel work

  /// Loops over fewer quadrature points than this (a group of cells) run on one thread: for small meshes waking threads (and, when other processes compete for
  /// the cores, waiting at barriers) costs more than the work. Default 2048 (an eighth of it for loops that
  /// assemble a Hessian, several times the work per point); 0 makes every loop parallel.
  void set_parallel_threshold(Eigen::Index t) { parallel_threshold_ = t; }

  /// det F and ψ at every quadrature point, in one pass: each element's minimum det F and mean energy
  /// density, and the deformed volume.
  struct Deformation {
    Eigen::VectorXd min_J;           ///< per element, the smallest det F over its quadrature points
    Eigen::VectorXd energy_density;  ///< per element, Σ_q w_q ψ(F_q) / Σ_q w_q (+∞ where ψ is undefined)
    double volume = 0.0;             ///< Σ_e Σ_q w_q det F_q (signed)
    /// Per element, α of its fibres' active strain (0 for a cell without); empty when the term has no fibres.
    Eigen::VectorXd contraction;
  };
  [[nodiscard]] Deformation deformation(const Eigen::VectorXd& x) const;

 private:
  /// Energy, and when asked the gradient (added to *gradient) and the Hessian (added through scatter).
  double assemble(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const std::vector<int>* scatter, double* values,
                  PsdProjection projection) const;
  /// Calls body(material, rest, pieces, piece_count, count) for each group of cells of one colour and one
  /// material, in group order: its count cells are group_cells_[pieces[p] .. pieces[p + 1]) for p <
  /// piece_count, pieces that share no vertex with each other.
  template <class Body>
  void for_each_group(Body&& body) const;
  /// Calls body(material, rest, begin, end) for each run of consecutive cells [begin, end) of one material, in
  /// cell order: for work that adds into no shared vertex (an energy alone, per-cell values), where cell order
  /// keeps neighbouring cells' vertices and rest data together in memory.
  template <class Body>
  void for_each_run(Body&& body) const;

  VolumeMesh mesh_;
  std::vector<AnyMaterial> materials_;
  std::vector<int> material_of_;                  ///< per cell (empty: all materials_[0])
  std::vector<int> fibre_of_;                     ///< per cell, its fibres in fibres_ or −1 (empty: none)
  std::vector<CellFibre> fibres_;
  RestState rest_;                                ///< distinct records (share_rest())
  std::vector<int> rest_of_cell_;                 ///< per cell, its record in rest_
  [[nodiscard]] std::size_t record(Eigen::Index c) const { return static_cast<std::size_t>(rest_of_cell_[static_cast<std::size_t>(c)]); }
  std::vector<int> scatter_;        ///< for the bound layout
  std::vector<int> group_cells_;  ///< cells grouped by colour, then material
  std::vector<int> group_start_;  ///< group k M + m (colour k, material m) owns group_cells_[group_start_[g] .. [g+1])
  std::vector<int> piece_start_;  ///< the groups' pieces, each from piece_start_[p] to [p + 1] in group_cells_
  std::vector<int> group_pieces_;  ///< group g's pieces are p = group_pieces_[g] .. [g + 1]
  Eigen::Index chunk_cells_ = 1;
  Eigen::Index parallel_threshold_ = 2048;
};

}  // namespace snh
