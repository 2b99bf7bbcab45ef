#pragma once
// Surface meshes (docs/design.md): OBJ, OFF, PLY (ASCII) and STL (ASCII and binary) triangle surfaces,
// read and checked, and turned into tetrahedra by Debian's `tetgen` program.
#include <filesystem>

#include <Eigen/Core>

#include "snh/io/mesh_read.hpp"

namespace snh {

struct SurfaceMesh {
  Eigen::Matrix3Xd vertices;
  Eigen::Matrix3Xi triangles;  ///< polygons are split into fans
  /// 3 by #vertices: an OBJ file's vertex normals ("vn", by the corners' v/vt/vn), the first a vertex's corners
  /// name; empty unless every vertex has one (and for the other formats).
  Eigen::Matrix3Xd normals;
};

/// Reads .obj, .off, .ply (ASCII) or .stl (ASCII or binary). STL's repeated corners are merged.
/// Throws MeshError ("FILE:LINE: ...").
[[nodiscard]] SurfaceMesh read_surface(const std::filesystem::path& path);

/// Tetrahedralizes a closed surface with `tetgen -pq1.414` (quality tets; with `max_volume` > 0 also
/// `-a max_volume`, no tet larger): writes it to a temporary directory, runs the program, reads its
/// .node/.ele. The surface's vertices stay vertices of the tets. Throws MeshError naming `source` when the
/// program is missing (with the Debian package to install) or fails.
[[nodiscard]] MeshFile tetrahedralize(const SurfaceMesh& surface, const std::filesystem::path& source,
                                      double max_volume = 0.0);

/// True for the extensions read_surface reads.
[[nodiscard]] bool is_surface_file(const std::filesystem::path& path);

}  // namespace snh
