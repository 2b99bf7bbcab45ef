#pragma once
// A hexahedral lattice embedding a closed surface (docs/design.md), as the paper's Figure 1: the cubes of
// a regular grid that overlap the solid, i.e. every cube a surface triangle passes through (an exact
// triangle-box overlap test) and every cube wholly inside (the winding number at its centre, asked once per
// connected region of cubes the surface does not touch). A cube in which the surface separates the material
// into pieces (two fingers, a hand resting on a thigh) becomes one cell per piece, and cells share a node
// only where their material is connected (the virtual node algorithm, Molino et al. 2004).
#include <cstdint>
#include <utility>
#include <array>
#include <vector>

#include <Eigen/Core>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

struct Lattice {
  VolumeMesh mesh;            ///< hex8 cells in VolumeMesh corner order; only the vertices the cells use
  Eigen::Vector3d origin;     ///< the grid's lowest corner
  double spacing = 0.0;       ///< the cubes' edge length
  Eigen::Vector3i dims;       ///< cubes along x, y, z
  std::vector<int> cell_at;   ///< dims.prod(): the (first) cell of cube (i, j, k) at i + dims.x · (j + dims.y · k), or −1
  // The pieces (virtual node algorithm). Each cube the surface meets is sampled at samples³ points (the
  // centres of its sub-cubes); two inside samples are connected when the segment between them stays inside
  // the solid (the winding number, which jumps by ±1 at each triangle it crosses, stays above ½ in magnitude:
  // a surface inside the solid, where two meshes overlap, does not separate), and a piece of a cube is a
  // connected set of its inside samples. A cube with several pieces has a cell per piece (cells of one cube
  // are consecutive, in order of their pieces' first samples).
  int samples = 0;                       ///< samples per cube edge (0: pieces not sought, one cell per cube)
  std::vector<int> cube_of_cell;         ///< per cell: its cube
  std::vector<int> piece_of_cell;        ///< per cell: its piece in the cube (0 in a cube of one cell)
  std::vector<int> copies;               ///< per vertex: how many vertices sit at its grid node (1 but at a split)
  std::vector<int> touched;              ///< the cubes a triangle meets, ascending
  std::vector<signed char> sample_piece; ///< samples³ per touched cube (sample a + s(b + s c)): piece, or −1 outside
  std::vector<float> sample_winding;     ///< the same samples' winding numbers
  std::vector<std::int64_t> triangle_start;  ///< per touched cube: its triangles in triangle[start[t] .. start[t+1])
  std::vector<int> triangle;
  int split_cubes = 0;                   ///< cubes with more than one cell
  [[nodiscard]] int cube_index(int i, int j, int k) const { return i + dims.x() * (j + dims.y() * k); }
  /// The (i, j, k) of cube index c (cube_index's inverse).
  [[nodiscard]] Eigen::Vector3i cube_ijk(int c) const {
    return {c % dims.x(), (c / dims.x()) % dims.y(), c / (dims.x() * dims.y())};
  }
  /// The slot of a cube in `touched`, or −1.
  [[nodiscard]] int touched_slot(int cube) const;
  /// The cells of cube `cube` (none: an empty range).
  [[nodiscard]] std::pair<int, int> cells_of_cube(int cube) const;
  /// The positions of the inside samples of a cell's piece (3 by #samples; a cube no triangle meets: all).
  [[nodiscard]] Eigen::Matrix3Xd cell_samples(int cell) const;
  /// A point in cube units: cube (i, j, k) spans [i, i+1] × [j, j+1] × [k, k+1]. The lattice is built and
  /// points are embedded with this one expression, so a surface vertex finds the cubes its triangles marked.
  [[nodiscard]] Eigen::Vector3d grid_coordinates(const Eigen::Vector3d& p) const { return (p - origin) / spacing; }
};

/// The lattice of a surface with `resolution` cubes along the bounding box's longest side (the grid padded by
/// a small fraction of a cube so no surface point lies on its outer faces). A cube is kept when a triangle
/// overlaps it (separating axes, the cube grown by 1e-9 of its edge so a point on a shared face counts for
/// the cubes on both sides) or when its centre is inside: |winding number| > ½, so either orientation, and
/// overlapping parts, count (Jacobson et al. 2013's generalized winding number: holes tolerated). On a closed
/// surface the winding number is asked once per region of untouched cubes (face neighbours), on an open one
/// at every untouched cube. Cells and vertices are numbered in grid order (x fastest).
/// With samples > 0 a cube the surface splits gets a cell per piece (see Lattice); a cube whose material the
/// samples miss (a sliver thinner than a sample's spacing) keeps one cell. Two cells of face-neighbour cubes
/// share the face's nodes when a pair of inside samples facing each other across the face is connected;
/// between cubes of one piece each the face is shared unless both have inside samples facing the face and no
/// such pair is connected (the surface runs between them), so a lattice with nothing to separate is exactly
/// the lattice without pieces. Material thinner than about a sample's spacing is not separated.
/// Throws std::invalid_argument for resolution < 1, samples < 0 or > 16, a non-finite vertex, an index out
/// of range, no triangles, a surface with no extent, or a grid of more than 2^28 cubes.
///   V  3 by #V (the bounding box is that of the vertices F uses);  F  3 by #F (a closed surface, or a soup)
[[nodiscard]] Lattice lattice_for_surface(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution,
                                          int samples = 4);

/// The grid lattice_for_surface would use (origin, spacing and dims only: no cells), so that several surfaces
/// can be given lattices on one grid (a character's meshes kept apart, build_flesh). Throws as lattice_for_surface.
[[nodiscard]] Lattice lattice_grid(const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int resolution);
/// lattice_for_surface on a given grid (from lattice_grid): the triangles of F must lie within it.
[[nodiscard]] Lattice lattice_on_grid(const Lattice& grid, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F, int samples = 4);

/// Separating-axis test of a triangle against the cube [−e, e]³ (Akenine-Möller 2001's 13 axes: the
/// cube's normals, the triangle's normal, and the 9 products of an edge with a cube axis). v: the corners
/// relative to the cube's centre. A degenerate triangle (a segment or a point) is tested exactly as well:
/// its zero normal separates nothing and the other axes are those of a segment.
[[nodiscard]] bool triangle_overlaps_cube(const std::array<Eigen::Vector3d, 3>& v, double e);

/// Whether the segment [p, q] meets the triangle (a, b, c), touching included (a segment in the triangle's
/// plane counts as not meeting it).
[[nodiscard]] bool segment_meets_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

}  // namespace snh
