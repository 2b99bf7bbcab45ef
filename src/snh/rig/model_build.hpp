#pragma once
// What the model readers (rig/gltf.cpp, rig/assimp.cpp) share once a file is parsed: the checks on the file
// itself, one-line messages, TRS from a matrix, welding the skin by position, folding the transforms of
// nodes between joints into clips' keys, and the final check of the rest pose. Internal to the rig layer.
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/rig/model.hpp"

namespace snh::rig_build {

/// Model files larger than this are refused before they are read.
inline constexpr std::uintmax_t max_file_bytes = std::uintmax_t{1} << 30;
/// The largest coordinate a model may have (a vertex, a node's translation): beyond it volumes and capsule
/// radii overflow (a vertex at 3e38 made the skin "enclose no volume").
inline constexpr double max_coordinate = 1e12;

/// Text from a file or a library on one line: its lines joined by "; ", other control characters as spaces.
[[nodiscard]] std::string one_line(std::string_view text);

/// Throws RigError("FILE: what").
[[noreturn]] void fail(const std::filesystem::path& path, const std::string& what);

/// Checks that `path` names a readable regular file of 1 byte to max_file_bytes (`kind` names what it should
/// be in the messages: "glTF", "model"); returns its size.
std::uintmax_t check_file(const std::filesystem::path& path, std::string_view kind);

/// A skin as a reader gathers it, mesh after mesh: positions, four joints and weights per vertex, triangles.
struct SkinData {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<Eigen::Vector4i> jidx;
  std::vector<Eigen::Vector4d> jw;
  std::vector<Eigen::Vector3i> tri;
  std::vector<Eigen::Vector2d> uv;      ///< kept only while every vertex so far has them
  std::vector<Eigen::Vector3d> normal;  ///< likewise
  bool all_uv = true, all_normals = true;
  /// Into the model's vertices, joint_index, joint_weight and triangles (uv and normals where every vertex has them).
  void store(RiggedModel& out) const;
};

/// Translation · rotation · scale from a 4 by 4 affine matrix. Returns an empty string and sets `out`, or the
/// reason it cannot be decomposed (not finite, not affine, a zero or negative scale, a shear).
[[nodiscard]] std::string decompose(const Eigen::Matrix4d& m, Transform& out);

/// Fills surface_vertices, surface_triangles and weld from vertices and triangles: vertices at the same
/// position (bitwise, +0 and −0 alike) merged in order of first appearance; triangles that lose a corner to
/// the merge dropped from the welded surface.
void weld(RiggedModel& model);

/// Where a joint node hangs in a node tree whose other nodes are folded away: the product of the transforms
/// of the nodes strictly between `node` and its nearest ancestor that is a joint (outermost first), and that
/// ancestor's joint (−1 when none: the nodes up to the root are folded in).
///   parent         per node, its parent node or −1
///   joint_of_node  per node, its joint or −1
///   local          local(n): node n's transform, a 4 by 4 matrix
template <class Local>
std::pair<Eigen::Matrix4d, int> joint_above(int node, const std::vector<int>& parent, const std::vector<int>& joint_of_node,
                                            const Local& local) {
  Eigen::Matrix4d between = Eigen::Matrix4d::Identity();
  int p = parent[static_cast<std::size_t>(node)];
  while (p >= 0 && joint_of_node[static_cast<std::size_t>(p)] < 0) {
    between = local(p) * between;
    p = parent[static_cast<std::size_t>(p)];
  }
  return {between, p >= 0 ? joint_of_node[static_cast<std::size_t>(p)] : -1};
}

/// A channel of a joint below non-joint nodes whose transforms `between` were folded into its rest transform:
/// its keys made relative to the joint's parent (or the model) too. Those nodes must scale uniformly.
void fold_in(const std::filesystem::path& path, const Eigen::Matrix4d& between, Channel& channel, const std::string& joint);

/// The rest pose, its skinning matrices and the skin at rest are finite (finite values can still overflow when
/// composed); throws RigError naming the joint or vertex.
void check_rest(const RiggedModel& model);

}  // namespace snh::rig_build
