#pragma once
// Rigged characters from glTF 2.0 files (docs/design.md), read by tinygltf (Debian's libtinygltf-dev):
// a skinned triangle mesh (.glb, or .gltf with external or embedded buffers), its skin (joints, inverse
// bind matrices, four joint weights per vertex), the joints' hierarchy and rest transforms, and its
// animation clips.
#include <filesystem>

#include "snh/rig/model.hpp"

namespace snh {

/// Reads a skinned character from a .glb or .gltf file: every skinned mesh node of the default scene that uses
/// the first one's skin (all their triangle primitives, one after the other: `parts`). Transforms of nodes between a joint and its parent joint (or the scene root)
/// are folded into its rest transform, and into its clips' keys (those nodes must then scale uniformly).
/// Throws RigError naming the file and the fault: not glTF, truncated, no skinned mesh, a primitive that is
/// not triangles, weights or joints out of range, a non-finite value, a sparse accessor, more than four
/// joint influences (a non-zero WEIGHTS_1), a file over 1 GiB.
[[nodiscard]] RiggedModel read_gltf(const std::filesystem::path& path);

}  // namespace snh
