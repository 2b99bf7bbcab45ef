#pragma once
// Wavefront OBJ frames in the paper programs' format (docs/paper-programs.md): `v x y z` for every vertex in
// index order, then `f a b c` (1-based) for every boundary triangle.
#include <filesystem>
#include <string>
#include <string_view>

#include <Eigen/Core>

namespace snh {

/// Writes the frame atomically.
///   path       output file
///   positions  3 by #V
///   triangles  3 by #F, 0-based vertex indices (written 1-based)
void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix3Xi& triangles);

/// The `f a b c` lines of write_obj for triangles (3 by #F, 0-based), made once for frames that share them;
/// with texture coordinates and/or normals of the same index per vertex, `f a/a/a`, `f a/a` or `f a//a`.
[[nodiscard]] std::string obj_faces(const Eigen::Matrix3Xi& triangles, bool texcoords = false, bool normals = false);

/// write_obj with the face lines made by obj_faces.
void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, std::string_view faces);

/// A character's frame: the vertices, then `vt u v` per vertex when `texcoords` (2 by #V) has columns, `vn x y z`
/// per vertex when `normals` (3 by #V) has columns, and faces that name them (`f a/a/a`, `f a/a` or `f a//a`:
/// each vertex's texture coordinate and normal have its own index).
void write_obj(const std::filesystem::path& path, const Eigen::Matrix3Xd& positions, const Eigen::Matrix2Xd& texcoords,
               const Eigen::Matrix3Xd& normals, const Eigen::Matrix3Xi& triangles);

}  // namespace snh
