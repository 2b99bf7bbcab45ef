#pragma once
// Rigged characters in the formats rigs also come in (FBX, COLLADA, DirectX .x, IQM, MS3D, SMD, MD5, …),
// read by Debian's assimp (libassimp-dev) and mapped onto the same model as glTF (rig/model.hpp).
#include <filesystem>

#include "snh/rig/model.hpp"

namespace snh {

/// Reads a skinned character through assimp (docs/flesh.md "Formats"): every mesh with bones, found depth
/// first through the node tree (triangulated; points and lines left out; at most four joints per vertex, the
/// strongest, their weights renormalized).
///   Joints  the nodes the bones name, and every animated ancestor of one (a hips node that moves the
///           skeleton but weighs no vertex), in depth-first order; the transforms of other nodes between a
///           joint and its parent joint (or the root) are folded into its rest transform and keys.
///   Skin    skinning takes a vertex v to Σ w · joint world · offset · v; at the bind pose the skin is where
///           the bones were bound, which an FBX's offsets put in the mesh node's frame and a DirectX .x file's
///           (as glTF's) in the model's: of the two, the one where the rest pose binds the bones best. A later
///           mesh that shares a bone with those before is taken into their space by that bone's offsets, so that
///           all share one inverse bind matrix per joint (meshes that cannot be are refused, naming both); a
///           joint no bone names gets the inverse of its rest frame. A vertex no bone weighs follows the
///           nearest joint above its mesh's node, or is refused.
///   Clips   each animation's node channels on joints, keys at tick / ticks-per-second seconds (25 ticks a
///           second where the file gives none), linear (rotations slerped).
/// Throws RigError naming the file and the fault (assimp's own message when it cannot read the file).
[[nodiscard]] RiggedModel read_assimp(const std::filesystem::path& path);

}  // namespace snh
