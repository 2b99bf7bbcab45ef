#pragma once
// Rigged characters from glTF 2.0 files (docs/design.md), read by tinygltf (Debian's libtinygltf-dev):
// a skinned triangle mesh (.glb, or .gltf with external or embedded buffers), its skin (joints, inverse
// bind matrices, four joint weights per vertex), the joints' hierarchy and rest transforms, and its
// animation clips.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "snh/rig/animation.hpp"
#include "snh/rig/skeleton.hpp"

namespace snh {

/// A model that cannot be used; the message is one line: "FILE: what is wrong".
class RigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// One skinned mesh of a model: its vertices are a range of the model's.
struct ModelPart {
  std::string name;                ///< the node's name (or "meshN")
  Eigen::Index first_vertex = 0, vertices = 0;
};

struct RiggedModel {
  std::filesystem::path source;
  std::vector<ModelPart> parts;    ///< the skinned meshes read, in the model's vertex order
  std::vector<std::string> skipped;  ///< skinned meshes of another skin than the first one's, not read
  // The render surface as the file has it (its vertex order, seams and all):
  Eigen::Matrix3Xd vertices;       ///< 3 by #v, model space, at the bind pose
  Eigen::Matrix3Xi triangles;      ///< 3 by #t, 0-based, counter-clockwise seen from outside
  Eigen::Matrix4Xi joint_index;    ///< 4 by #v: skin joints (indices into skeleton.joints)
  Eigen::Matrix4Xd joint_weight;   ///< 4 by #v: their weights, summing to 1
  // The same surface welded by position (a solid's boundary, or a soup of open and overlapping parts):
  Eigen::Matrix3Xd surface_vertices;  ///< 3 by #s
  Eigen::Matrix3Xi surface_triangles; ///< 3 by #t, the model's triangles on welded vertices
  std::vector<int> weld;              ///< #v: the welded vertex of each model vertex
  Skeleton skeleton;                  ///< the skin's joints, in the skin's order
  std::vector<Eigen::Matrix4d> inverse_bind;  ///< per joint
  std::vector<Clip> clips;
  /// How the hierarchy was found: "file" (the nodes' children), or "names" (a skin whose joints are all
  /// siblings, as WebXR hands store them: the chain rebuilt from the WebXR Hand Input joint names, every
  /// joint's world rest transform kept; not done when a clip animates the joints, whose keys are local to
  /// the file's flat hierarchy).
  std::string hierarchy = "file";
};

/// Reads a skinned character from a .glb or .gltf file: every skinned mesh node of the default scene that uses
/// the first one's skin (all their triangle primitives, one after the other: `parts`). Transforms of nodes between a joint and its parent joint (or the scene root)
/// are folded into its rest transform, and into its clips' keys (those nodes must then scale uniformly).
/// Throws RigError naming the file and the fault: not glTF, truncated, no skinned mesh, a primitive that is
/// not triangles, weights or joints out of range, a non-finite value, a sparse accessor, more than four
/// joint influences (a non-zero WEIGHTS_1), a file over 1 GiB.
[[nodiscard]] RiggedModel read_gltf(const std::filesystem::path& path);

/// The clip played when none is named: the first that lasts and moves (a zero-length or still "bind" clip
/// skipped), else clip 0; −1 for a model without clips.
[[nodiscard]] int default_clip(const RiggedModel& model);

/// The clip of this name, or of this 0-based index written in decimal. Throws RigError listing the clips.
[[nodiscard]] const Clip& find_clip(const RiggedModel& model, const std::string& name_or_index);

}  // namespace snh
