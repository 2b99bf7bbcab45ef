#pragma once
// A rigged, animated character as snh uses it (docs/design.md), whatever file it came from: the skinned
// meshes at the bind pose, four joint weights per vertex, the skeleton with its rest transforms and inverse
// bind matrices, and the animation clips. read_model reads glTF 2.0 itself (rig/gltf.hpp) and the formats
// rigs also come in (FBX, COLLADA, DirectX .x, …) through Debian's assimp (rig/assimp.hpp).
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
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
  std::string format;              ///< the file's format as its reader names it ("glTF 2.0", "FBX", "DirectX .x", …)
  std::vector<ModelPart> parts;    ///< the skinned meshes read, in the model's vertex order
  std::vector<std::string> skipped;  ///< skinned meshes of another skin than the first one's, not read
  std::vector<std::string> notes;    ///< what the reader made of faults it could work around, one line each
  /// The file's length unit in metres and up axis, where it says (FBX: UnitScaleFactor, in centimetres, and
  /// UpAxis with its sign); else metres and +Y, as glTF has them. snh keeps the file's coordinates; these say
  /// what they mean (flesh.usda's metersPerUnit and upAxis, the header).
  double meters_per_unit = 1.0;
  int up_axis = 1;                 ///< 0, 1, 2: x, y, z
  int up_sign = 1;                 ///< +1 or −1
  // The render surface as the file has it (its vertex order, seams and all):
  Eigen::Matrix3Xd vertices;       ///< 3 by #v, model space, at the bind pose
  Eigen::Matrix3Xi triangles;      ///< 3 by #t, 0-based, counter-clockwise seen from outside
  Eigen::Matrix4Xi joint_index;    ///< 4 by #v: skin joints (indices into skeleton.joints)
  Eigen::Matrix4Xd joint_weight;   ///< 4 by #v: their weights, summing to 1
  /// 2 by #v: the first texture coordinates, origin at the image's bottom left as OBJ and USD have it (glTF's
  /// v flipped); empty unless every mesh read has them.
  Eigen::Matrix2Xd uv;
  Eigen::Matrix3Xd normals;        ///< 3 by #v: unit normals at the bind pose; empty unless every mesh has them
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

/// `name` with its control characters (bytes below 0x20, and 0x7f) written as \xNN.
[[nodiscard]] std::string printable_name(std::string_view name);

/// Reads a rigged character: .gltf and .glb by read_gltf, every other file by read_assimp. Throws RigError.
/// The joints', meshes' and clips' names are made printable (printable_name).
[[nodiscard]] RiggedModel read_model(const std::filesystem::path& path);

/// The clip played when none is named: the first that lasts and moves (a zero-length or still "bind" clip
/// skipped), else clip 0; −1 for a model without clips.
[[nodiscard]] int default_clip(const RiggedModel& model);

/// The clip of this name, or of this 0-based index written in decimal. Throws RigError listing the clips.
[[nodiscard]] const Clip& find_clip(const RiggedModel& model, const std::string& name_or_index);

}  // namespace snh
