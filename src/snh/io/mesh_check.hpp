#pragma once
// The checks every volume mesh read from a file passes (docs/design.md): what a reader cannot see from
// one line alone (ranges, repeats, unused vertices, degenerate or inverted cells).
#include <filesystem>

#include "snh/io/mesh_file.hpp"

namespace snh {

/// The supported magnitude of mesh coordinates (cell volumes stay far from overflow).
inline constexpr double kMaxCoordinate = 1e20;

/// Checks a mesh read from `file`: finite coordinates within |x| <= kMaxCoordinate, indices in range and not repeated within a cell,
/// no unreferenced vertex, no degenerate cell (|volume| below 1e-10 of the mean cell volume), no hex with a
/// corner Jacobian of the opposite sign to its volume (bow-tie, folded); cells with
/// negative rest volume are re-oriented (counted in `reoriented`). Throws MeshError.
///   m     the mesh as read, with the line of each cell where known; re-oriented in place
///   file  the file it was read from, named in every error
void check_mesh(MeshFile& m, const std::filesystem::path& file);

}  // namespace snh
