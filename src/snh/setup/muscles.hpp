#pragma once
// A scene's tissues and muscles built on its body (docs/muscles.md): each region's cells (those whose rest
// centre lies in its box, its closed surface or its model mesh), their materials, a muscle's fibres (a
// constant direction, or the gradient of a harmonic field from origin to insertion, docs/math.md §14.4),
// its activation over time (keyframes, or a line of action between two joints' points) and the active strain
// that activation sets in the simulation (SimulationSetup::fibre_strain); tissues bound to a joint become a
// kinematic set.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include "snh/fem/elastic_term.hpp"
#include "snh/material/registry.hpp"
#include "snh/setup/scene.hpp"
#include "snh/sim/kinematics.hpp"

namespace snh {

struct SceneBody;

struct BuiltMuscles {
  std::vector<AnyMaterial> materials;   ///< [0] the scene's, then one per region that gives its own
  std::vector<int> material_of_cell;    ///< #C indices into materials
  std::vector<int> region_of_cell;      ///< #C: the entry of scene.muscles that holds the cell, or −1
  std::vector<int> fibre_of_cell;       ///< #C indices into fibres, or −1 (empty: no muscle)
  std::vector<CellFibre> fibres;        ///< a muscle's: one (a constant direction) or one per cell (a field)
  struct Muscle {
    std::string name;
    int spec = 0;                       ///< its entry in scene.muscles
    int first_fibre = 0, fibre_count = 0;  ///< its entries of fibres
    double contraction = 0.0;
    std::function<double(double t)> activation;  ///< in [0, 1]
  };
  std::vector<Muscle> muscles;
  std::vector<KinematicSet> bones;      ///< tissues bound whole to a joint
  std::vector<std::string> summary;     ///< one line per region, for the run's header

  /// Each muscle's activation at time t.
  [[nodiscard]] std::vector<double> activation(double t) const;
  /// Sets alpha (one per fibres entry) to γ · activation at time t (SimulationSetup::fibre_strain).
  void fibre_strain(double t, std::vector<double>& alpha) const;
};

/// muscles.json of a run (docs/muscles.md): per region its name, kind and cells; per muscle also its fibres
/// (per cell: the rest centre and the unit direction) and its activation at each of `times`.
[[nodiscard]] nlohmann::json muscles_json(const BuiltMuscles& muscles, const Scene& scene, const VolumeMesh& mesh,
                                          const std::vector<double>& times);

/// The scene's tissues and muscles on `body` (null when the scene has none). Reads the regions' surface files.
/// Throws SceneError (one line naming the scene file and the entry): a file that cannot be read, a region that
/// holds no cell, a joint or model mesh the model lacks, a harmonic field whose ends cannot be told apart.
[[nodiscard]] std::shared_ptr<const BuiltMuscles> build_muscles(const Scene& scene, const SceneBody& body);

/// The cells whose rest centre (the mean of their vertices) the surface (V, F) holds: a generalised winding
/// number of magnitude ½ or more. On a closed surface it is asked once per group of vertex-sharing cells
/// that no triangle's box touches (it is constant off the surface) and at each cell one touches; on an open
/// one at every cell in the surface's box. Throws std::invalid_argument for a non-finite vertex or an index
/// out of range.
[[nodiscard]] std::vector<int> cells_inside(const VolumeMesh& mesh, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F);

/// The vertices of `cells` where a muscle attaches at `point`: those within `reach` of the distance from the
/// point to the nearest of them (docs/muscles.md).
[[nodiscard]] std::vector<int> attachment_vertices(const VolumeMesh& mesh, const std::vector<int>& cells, const Eigen::Vector3d& point,
                                                   double reach);

/// The fibres of a harmonic field on `cells` of `mesh` (docs/math.md §14.4): u solves the Laplace equation on
/// those cells (their own shape functions, natural boundaries elsewhere) with u = 0 at the `origin` vertices
/// and 1 at the `insertion` vertices, and each cell's fibre is ∇u at its centre (the mean over its quadrature
/// points), normalised. A cell where ∇u vanishes (a part of the region that touches neither end) keeps
/// `fallback`. Throws std::invalid_argument (one line) when a vertex is in both ends, or either is empty.
[[nodiscard]] std::vector<Eigen::Vector3d> harmonic_fibres(const VolumeMesh& mesh, const std::vector<int>& cells,
                                                          const std::vector<int>& origin, const std::vector<int>& insertion,
                                                          const Eigen::Vector3d& fallback);

}  // namespace snh
