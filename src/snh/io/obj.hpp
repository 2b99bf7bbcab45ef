#pragma once
// Wavefront OBJ frames in the paper programs' format (PAPER_CODE.md): `v x y z` for every vertex in
// index order, then `f a b c` (1-based) for every boundary triangle.
#include <filesystem>

#include <Eigen/Core>

namespace snh {

/// Writes the frame atomically.
///   path       output file
///   positions  3 by #V
///   triangles  3 by #F, 0-based vertex indices (written 1-based)
void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles);

}  // namespace snh
