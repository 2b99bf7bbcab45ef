#pragma once
// Points embedded in a volume mesh (docs/design.md): each point stores a cell and the weights of that
// cell's vertices at rest (trilinear in a lattice cube, barycentric in a tet), so that it follows the
// deformed volume as x = Σ w_i x_i.
#include <vector>

#include <Eigen/Core>

#include "snh/embed/lattice.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh {

struct Embedding {
  std::vector<int> cell;    ///< #p: the cell holding each point
  Eigen::MatrixXi vertex;   ///< k by #p (k = 8 for hexes, 4 for tets): the cell's vertices
  Eigen::MatrixXd weight;   ///< k by #p: their weights (sum 1)

  /// The points for volume positions X (3 by #V of the mesh embedded in): 3 by #p.
  [[nodiscard]] Eigen::Matrix3Xd apply(const Eigen::Matrix3Xd& X) const;
  /// The same for a flat 3 #V position vector.
  [[nodiscard]] Eigen::Matrix3Xd apply(const Eigen::VectorXd& x) const;
};

/// Trilinear weights of points in the lattice's cubes: the cube floor((p − origin) / spacing), else one whose
/// face the point is on (within 1e-6 of the spacing), e.g. a neighbour kept where that cube is not. Throws
/// std::invalid_argument naming the first point that lies in no cube of the lattice (or is not finite).
///   points  3 by #p
/// In a cube the surface splits into pieces (Lattice), a point goes with the piece of its nearest inside sample.
[[nodiscard]] Embedding embed_in_lattice(const Lattice& lattice, const Eigen::Matrix3Xd& points);
/// The same for points on the surface (V, F) the lattice was built from, point p being its vertex vertex[p]:
/// in a split cube, the piece of the nearest inside sample that the point sees (the segment to it meets no
/// triangle but the vertex's own), so that a fingertip's skin goes with its finger, not the one beside it.
[[nodiscard]] Embedding embed_surface_in_lattice(const Lattice& lattice, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F,
                                                 const Eigen::Matrix3Xd& points, const std::vector<int>& vertex);

/// Barycentric weights of points in a tet mesh: the tet containing each point (on a shared face, the one
/// whose smallest barycentric coordinate is largest); a point outside every tet by more than 1e-6 of the
/// mesh's size (its bounding box's diagonal) is an error (std::invalid_argument naming it); one just outside
/// takes, of the tets it is that close to, the one whose smallest coordinate is largest, its coordinates
/// clamped to ≥ 0 and renormalised. A point equal to a tet's vertex gets weight exactly 1 there. Tets are
/// found through a uniform grid of their bounding boxes.
[[nodiscard]] Embedding embed_in_tets(const VolumeMesh& tets, const Eigen::Matrix3Xd& points);

}  // namespace snh
