#include "snh/rig/assimp.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/config.h>
#include <assimp/importerdesc.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>
#include <fmt/format.h>

#include "snh/rig/model_build.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using rig_build::one_line;

Eigen::Matrix4d matrix(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return out;
}

std::string name_of(const aiString& s) { return std::string(s.C_Str(), s.length); }

/// "Autodesk FBX Importer" → "Autodesk FBX".
std::string strip_importer(std::string name) {
  constexpr std::string_view suffix = " Importer";
  if (name.size() > suffix.size() && name.ends_with(suffix)) name.resize(name.size() - suffix.size());
  return name;
}

/// A vertex's four strongest joints and their weights (a joint named twice has its weights added), and the
/// sum of those four weights (0 for a vertex no bone weighs).
std::tuple<Eigen::Vector4i, Eigen::Vector4d, double> strongest_four(std::vector<std::pair<double, int>> influences) {
  std::sort(influences.begin(), influences.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  std::vector<std::pair<double, int>> merged;
  for (const auto& [w, j] : influences)
    if (!merged.empty() && merged.back().second == j) merged.back().first += w;
    else merged.emplace_back(w, j);
  std::stable_sort(merged.begin(), merged.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  if (merged.size() > 4) merged.resize(4);
  Eigen::Vector4i j = Eigen::Vector4i::Zero();
  Eigen::Vector4d w = Eigen::Vector4d::Zero();
  double sum = 0.0;
  for (std::size_t q = 0; q < merged.size(); ++q) {
    w(static_cast<Eigen::Index>(q)) = merged[q].first;
    j(static_cast<Eigen::Index>(q)) = merged[q].second;
    sum += merged[q].first;
  }
  return {j, w, sum};
}

/// Builds a RiggedModel from an assimp scene; every fault is a RigError naming the file.
class SceneReader {
 public:
  SceneReader(const fs::path& path, const aiScene& scene) : path_(path), s_(scene) {}

  RiggedModel build(std::string format) {
    RiggedModel out;
    out.source = path_;
    out.format = std::move(format);
    list_nodes();
    find_skinned_meshes();
    choose_joints(out);
    read_meshes(out);
    rig_build::weld(out);
    read_animations(out);
    rig_build::check_rest(out);
    read_units(out);
    return out;
  }

 private:
  /// A number of the scene's metadata (FBX's global settings), if it is there.
  std::optional<double> meta_number(const char* key) const {
    const aiMetadata* m = s_.mMetaData;
    if (m == nullptr) return std::nullopt;
    for (unsigned k = 0; k < m->mNumProperties; ++k) {
      if (std::string(m->mKeys[k].C_Str()) != key) continue;
      const aiMetadataEntry& e = m->mValues[k];
      switch (e.mType) {
        case AI_BOOL: return *static_cast<const bool*>(e.mData) ? 1.0 : 0.0;
        case AI_INT32: return *static_cast<const std::int32_t*>(e.mData);
        case AI_UINT64: return static_cast<double>(*static_cast<const std::uint64_t*>(e.mData));
        case AI_FLOAT: return *static_cast<const float*>(e.mData);
        case AI_DOUBLE: return *static_cast<const double*>(e.mData);
        default: return std::nullopt;
      }
    }
    return std::nullopt;
  }

  /// The unit and up axis the file declares (FBX), said in a note when they are not metres and +Y.
  void read_units(RiggedModel& out) const {
    if (const auto f = meta_number("UnitScaleFactor"); f && std::isfinite(*f) && *f > 0.0) {
      out.meters_per_unit = *f / 100.0;
      if (*f != 100.0)
        out.notes.push_back(fmt::format("units: the file says 1 unit = {:g} cm (UnitScaleFactor): {:g} m per unit, kept as they are "
                                        "(flesh.usda says so; a dynamic run's E, density and gravity are in these units)",
                                        *f, out.meters_per_unit));
    }
    if (const auto axis = meta_number("UpAxis"); axis && (*axis == 0.0 || *axis == 1.0 || *axis == 2.0)) {
      out.up_axis = static_cast<int>(*axis);
      const auto sign = meta_number("UpAxisSign");
      out.up_sign = sign && *sign < 0.0 ? -1 : 1;
      if (out.up_axis != 1 || out.up_sign != 1)
        out.notes.push_back(fmt::format("up axis: the file says {}{} (UpAxis), kept as it is (flesh.usda says so where USD can: +Y or +Z; "
                                        "--ground and --dynamic's gravity act along y)",
                                        out.up_sign < 0 ? "-" : "+", "XYZ"[out.up_axis]));
    }
  }

  [[noreturn]] void fail(const std::string& what) const { rig_build::fail(path_, what); }

  std::string node_label(int n) const { return fmt::format("node \"{}\"", one_line(name_of(nodes_[static_cast<std::size_t>(n)]->mName))); }

  /// Every node depth first from the root, with its parent and its transform relative to the root at rest.
  void list_nodes() {
    if (s_.mRootNode == nullptr) fail("the file holds no node tree");
    std::vector<std::pair<const aiNode*, int>> stack{{s_.mRootNode, -1}};
    while (!stack.empty()) {
      const auto [node, parent] = stack.back();
      stack.pop_back();
      const int i = static_cast<int>(nodes_.size());
      if (nodes_.size() > 1000000) fail("more than a million nodes");
      nodes_.push_back(node);
      parent_.push_back(parent);
      const Eigen::Matrix4d local = matrix(node->mTransformation);
      if (!local.allFinite()) fail(fmt::format("{} has a transform that is not finite", node_label(i)));
      global_.push_back(parent < 0 ? local : Eigen::Matrix4d(global_[static_cast<std::size_t>(parent)] * local));
      const std::string name = name_of(node->mName);
      by_name_.try_emplace(name, i);  // the first node of a name (depth first) is the one bones and channels name
      for (unsigned c = node->mNumChildren; c-- > 0;) stack.emplace_back(node->mChildren[c], i);
    }
  }

  /// The meshes with bones and triangles, in the order their nodes come depth first (a mesh two nodes show,
  /// once, with the first node).
  void find_skinned_meshes() {
    std::vector<char> seen(s_.mNumMeshes, 0);
    for (std::size_t n = 0; n < nodes_.size(); ++n)
      for (unsigned k = 0; k < nodes_[n]->mNumMeshes; ++k) {
        const unsigned m = nodes_[n]->mMeshes[k];
        if (m >= s_.mNumMeshes) fail(fmt::format("{} refers to mesh {}, which does not exist", node_label(static_cast<int>(n)), m));
        if (seen[m]) continue;
        seen[m] = 1;
        const aiMesh* mesh = s_.mMeshes[m];
        if ((mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE) == 0) continue;
        (mesh->mNumBones == 0 ? rigid_ : meshes_).push_back({static_cast<int>(n), m});
      }
    if (meshes_.empty()) fail("no skinned mesh (no mesh with bones and triangles)");
  }

  /// The joints' world frames in the rest pose; a fault (a transform that overflows) names the file.
  std::vector<Eigen::Affine3d> rest_world(const RiggedModel& out) const {
    try {
      return out.skeleton.world(out.skeleton.rest_pose());
    } catch (const std::invalid_argument& e) {
      fail(fmt::format("at rest, {}", one_line(e.what())));
    }
  }

  /// The joint a bone moves.
  int joint_of_bone(const aiBone* b) const {
    const std::string name = name_of(b->mName);
    if (const auto it = by_name_.find(name); it != by_name_.end()) return joint_of_node_[static_cast<std::size_t>(it->second)];
    return nodeless_.at(name);
  }

  /// The joints: the bones' nodes and their animated ancestors, depth first; each joint's parent joint and
  /// rest transform (other nodes between them folded in).
  void choose_joints(RiggedModel& out) {
    std::vector<char> joint(nodes_.size(), 0), animated(nodes_.size(), 0);
    for (unsigned a = 0; a < s_.mNumAnimations; ++a)
      for (unsigned c = 0; c < s_.mAnimations[a]->mNumChannels; ++c)
        if (const auto it = by_name_.find(name_of(s_.mAnimations[a]->mChannels[c]->mNodeName)); it != by_name_.end())
          animated[static_cast<std::size_t>(it->second)] = 1;
    std::vector<std::string> nodeless;  // bones no node is named after, in the order met
    for (const auto& [node, m] : meshes_) {
      const aiMesh* mesh = s_.mMeshes[m];
      for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const std::string name = name_of(mesh->mBones[b]->mName);
        const auto it = by_name_.find(name);
        if (it == by_name_.end()) {
          if (std::find(nodeless.begin(), nodeless.end(), name) == nodeless.end()) nodeless.push_back(name);
          continue;
        }
        int n = it->second;
        joint[static_cast<std::size_t>(n)] = 1;
        for (n = parent_[static_cast<std::size_t>(n)]; n >= 0; n = parent_[static_cast<std::size_t>(n)])
          if (animated[static_cast<std::size_t>(n)]) joint[static_cast<std::size_t>(n)] = 1;
      }
    }
    joint_of_node_.assign(nodes_.size(), -1);
    for (std::size_t n = 0; n < nodes_.size(); ++n)
      if (joint[n]) {
        joint_of_node_[n] = static_cast<int>(joint_node_.size());
        joint_node_.push_back(static_cast<int>(n));
      }
    for (const int n : joint_node_) {
      Joint j;
      j.name = name_of(nodes_[static_cast<std::size_t>(n)]->mName);
      if (j.name.empty()) j.name = fmt::format("joint{}", out.skeleton.joints.size());
      const auto [between, above] = rig_build::joint_above(
          n, parent_, joint_of_node_, [&](int p) { return matrix(nodes_[static_cast<std::size_t>(p)]->mTransformation); });
      j.parent = above;
      const Eigen::Matrix4d rest = between * matrix(nodes_[static_cast<std::size_t>(n)]->mTransformation);
      if (const std::string why = rig_build::decompose(rest, j.rest); !why.empty())
        fail(fmt::format("the rest transform of joint {} (its ancestors' transforms folded in) {}", node_label(n), why));
      between_.push_back(between);
      out.skeleton.joints.push_back(std::move(j));
    }
    // A bone that no node is named after (an exporter that left it out of the hierarchy): a joint of its own
    // that never moves, so its vertices stay where the bind pose puts them.
    for (const std::string& name : nodeless) {
      nodeless_.emplace(name, static_cast<int>(joint_node_.size()));
      joint_node_.push_back(-1);
      Joint j;
      j.name = name.empty() ? fmt::format("joint{}", out.skeleton.joints.size()) : name;
      out.skeleton.joints.push_back(std::move(j));
      between_.push_back(Eigen::Matrix4d::Identity());
      out.notes.push_back(fmt::format("bone \"{}\" is in no node of the file's hierarchy: held at its bind pose", one_line(name)));
    }
  }

  /// Where a mesh's vertices go in the model: skinning takes a vertex v to Σ w · joint world · offset · v
  /// whatever this is, but the skin at the bind pose is M v, with M where the bones were bound. Files differ:
  /// an FBX's offsets map the mesh node's local space (M = the node's transform), a DirectX .x file's and a
  /// glTF's the model's (M = identity, the node's transform unused). M is the one of the two under which the
  /// rest pose binds the bones best (rest world · offset · M⁻¹ nearest the identity). A mesh after the first
  /// that shares a bound bone with those before is taken into their space by that bone's offsets.
  ///   rest      the joints' world frames at rest;  bound_by  per joint, the mesh that set its inverse bind, or −1
  Eigen::Matrix4d mesh_space(const RiggedModel& out, const std::vector<Eigen::Affine3d>& rest, const std::vector<int>& bound_by, int node,
                             const aiMesh* mesh) const {
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
      const int j = joint_of_bone(mesh->mBones[b]);
      if (bound_by[static_cast<std::size_t>(j)] >= 0)
        return out.inverse_bind[static_cast<std::size_t>(j)].inverse() * matrix(mesh->mBones[b]->mOffsetMatrix);
    }
    const auto misfit = [&](const Eigen::Matrix4d& space) {
      const Eigen::Matrix4d back = space.inverse();
      double sum = 0.0;
      for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const int j = joint_of_bone(mesh->mBones[b]);
        if (joint_node_[static_cast<std::size_t>(j)] < 0) continue;  // a bone in no node has no rest frame
        sum += (rest[static_cast<std::size_t>(j)].matrix() * matrix(mesh->mBones[b]->mOffsetMatrix) * back - Eigen::Matrix4d::Identity()).norm();
      }
      return sum;
    };
    const Eigen::Matrix4d& node_space = global_[static_cast<std::size_t>(node)];
    return misfit(node_space) < misfit(Eigen::Matrix4d::Identity()) ? node_space : Eigen::Matrix4d::Identity();
  }

  /// Each skinned mesh's vertices in the model's space, its triangles, and each vertex's four strongest joints.
  /// Where a mesh without bones at `node` goes: its joint (the node's own, or the nearest above it) and the
  /// matrix from the node's frame into the model at that joint's bind frame. False when no joint a skinned
  /// mesh binds is at or above it.
  bool rigid_place(const RiggedModel& out, const std::vector<int>& bound_by, int node, int& joint, Eigen::Matrix4d& place) const {
    Eigen::Matrix4d chain = Eigen::Matrix4d::Identity();
    joint = joint_of_node_[static_cast<std::size_t>(node)];
    if (joint < 0) {
      const auto [between, above] = rig_build::joint_above(
          node, parent_, joint_of_node_, [&](int p) { return matrix(nodes_[static_cast<std::size_t>(p)]->mTransformation); });
      chain = between * matrix(nodes_[static_cast<std::size_t>(node)]->mTransformation);
      joint = above;
    }
    if (joint < 0 || bound_by[static_cast<std::size_t>(joint)] < 0) return false;
    place = out.inverse_bind[static_cast<std::size_t>(joint)].inverse() * chain;
    return true;
  }

  /// A mesh's triangles (its points and lines skipped), numbered from `offset`; none is an error.
  void read_triangles(const aiMesh& mesh, int offset, const std::string& where, std::vector<Eigen::Vector3i>& tri) const {
    const std::size_t first_triangle = tri.size();
    for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
      const aiFace& face = mesh.mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines (a mesh of mixed primitives)
      Eigen::Vector3i t;
      for (int c = 0; c < 3; ++c) {
        if (face.mIndices[c] >= mesh.mNumVertices)
          fail(fmt::format("{}: face {} refers to vertex {}, but the mesh has {}", where, f, face.mIndices[c], mesh.mNumVertices));
        t(c) = offset + static_cast<int>(face.mIndices[c]);
      }
      tri.push_back(t);
    }
    if (tri.size() == first_triangle) fail(fmt::format("{}: no triangles", where));
  }

  void read_meshes(RiggedModel& out) {
    const std::size_t joints = joint_node_.size();
    out.inverse_bind.assign(joints, Eigen::Matrix4d::Identity());
    std::vector<int> bound_by(joints, -1);  // the mesh (index into meshes_) that set each joint's inverse bind
    const std::vector<Eigen::Affine3d> rest = rest_world(out);  // (the joints in no node rest at identity until bound)
    rig_build::SkinData data;
    auto& xyz = data.xyz;
    auto& jidx = data.jidx;
    auto& jw = data.jw;
    auto& tri = data.tri;
    // The skinned meshes, then the meshes without bones under a joint that a skinned mesh binds (an eye, a
    // prop parented to a bone), placed at that joint's bind frame and following it rigidly.
    std::vector<std::pair<int, unsigned>> todo = meshes_;
    todo.insert(todo.end(), rigid_.begin(), rigid_.end());
    for (std::size_t k = 0; k < todo.size(); ++k) {
      const auto [node, m] = todo[k];
      const aiMesh* mesh = s_.mMeshes[m];
      const std::string mesh_name = name_of(mesh->mName);
      const std::string where = fmt::format("mesh \"{}\"", one_line(mesh_name));
      const bool rigid = k >= meshes_.size();
      int rigid_joint = -1;
      Eigen::Matrix4d to_common;
      if (rigid) {
        if (!rigid_place(out, bound_by, node, rigid_joint, to_common)) continue;  // under no bound joint: not the character's
      } else {
        to_common = mesh_space(out, rest, bound_by, node, mesh);
      }
      const Eigen::Matrix4d from_common = to_common.inverse();
      if (!to_common.allFinite() || !from_common.allFinite())
        fail(fmt::format("{}: its offset matrices cannot be related to the other meshes'", where));
      if (xyz.size() + mesh->mNumVertices > static_cast<std::size_t>(std::numeric_limits<int>::max() / 4))
        fail(fmt::format("{}: too many vertices", where));
      const int offset = static_cast<int>(xyz.size());
      const std::size_t nv = mesh->mNumVertices;
      // Texture coordinates (assimp's origin is the image's bottom left, as OBJ's and USD's) and normals, taken
      // to the root's space as the positions are, where the mesh has them.
      data.all_uv = data.all_uv && mesh->mTextureCoords[0] != nullptr;
      data.all_normals = data.all_normals && mesh->mNormals != nullptr;
      const Eigen::Matrix3d normal_map = from_common.topLeftCorner<3, 3>().transpose();
      std::vector<std::vector<std::pair<double, int>>> influences(nv);
      for (unsigned b = 0; b < mesh->mNumBones; ++b) {
        const aiBone* bone = mesh->mBones[b];
        const int j = joint_of_bone(bone);
        const Eigen::Matrix4d ib = matrix(bone->mOffsetMatrix) * from_common;
        if (!ib.allFinite()) fail(fmt::format("{}: bone \"{}\" has an offset matrix that is not finite", where, one_line(name_of(bone->mName))));
        auto& set = bound_by[static_cast<std::size_t>(j)];
        Eigen::Matrix4d& stored = out.inverse_bind[static_cast<std::size_t>(j)];
        if (set < 0) {
          stored = ib;
          set = static_cast<int>(k);
        } else if ((stored - ib).cwiseAbs().maxCoeff() > 1e-5 * std::max(1.0, stored.cwiseAbs().maxCoeff())) {
          fail(fmt::format("{} and mesh \"{}\" bind bone \"{}\" in different poses (their offset matrices differ), which is not supported",
                           where, one_line(name_of(s_.mMeshes[meshes_[static_cast<std::size_t>(set)].second]->mName)),
                           one_line(name_of(bone->mName))));
        }
        for (unsigned w = 0; w < bone->mNumWeights; ++w) {
          const aiVertexWeight& vw = bone->mWeights[w];
          if (vw.mVertexId >= nv)
            fail(fmt::format("{}: bone \"{}\" weighs vertex {}, but the mesh has {}", where, one_line(name_of(bone->mName)), vw.mVertexId, nv));
          if (!std::isfinite(vw.mWeight) || vw.mWeight < 0.0f)
            fail(fmt::format("{}: bone \"{}\" gives vertex {} the weight {}", where, one_line(name_of(bone->mName)), vw.mVertexId, vw.mWeight));
          if (vw.mWeight > 0.0f) influences[vw.mVertexId].emplace_back(vw.mWeight, j);
        }
      }
      // A vertex no bone weighs follows the nearest joint at or above its mesh's node.
      int fallback = -1;
      for (int n = node; n >= 0 && fallback < 0; n = parent_[static_cast<std::size_t>(n)]) fallback = joint_of_node_[static_cast<std::size_t>(n)];
      std::size_t unweighted = 0;
      for (std::size_t v = 0; v < nv; ++v) {
        const aiVector3D& p = mesh->mVertices[v];
        const Eigen::Vector3d x = (to_common * Eigen::Vector4d(p.x, p.y, p.z, 1.0)).head<3>();
        if (!x.allFinite()) fail(fmt::format("{}: vertex {} has a position that is not finite", where, v));
        if (x.cwiseAbs().maxCoeff() > rig_build::max_coordinate)
          fail(fmt::format("{}: vertex {} has a coordinate of {:g}, beyond {:g}", where, v, x.cwiseAbs().maxCoeff(),
                           rig_build::max_coordinate));
        auto [j, w, sum] = strongest_four(influences[v]);
        if (!(sum > 0.0)) {
          if (fallback < 0) {
            ++unweighted;
            continue;
          }
          j(0) = fallback;
          w(0) = sum = 1.0;
        }
        if (data.all_uv) data.uv.emplace_back(mesh->mTextureCoords[0][v].x, mesh->mTextureCoords[0][v].y);
        if (data.all_normals) {
          const aiVector3D& nv3 = mesh->mNormals[v];
          Eigen::Vector3d nrm = normal_map * Eigen::Vector3d(nv3.x, nv3.y, nv3.z);
          if (!nrm.allFinite()) nrm.setZero();
          data.normal.push_back(nrm);
        }
        xyz.push_back(x);
        jidx.push_back(j);
        jw.push_back(w / sum);
      }
      if (unweighted > 0)
        fail(fmt::format("{}: {} of its {} vertices have no bone weights and no joint above the mesh to follow", where, unweighted, nv));
      read_triangles(*mesh, offset, where, tri);
      const std::string node_name = name_of(nodes_[static_cast<std::size_t>(node)]->mName);
      out.parts.push_back({.name = one_line(!mesh_name.empty() ? mesh_name : !node_name.empty() ? node_name : fmt::format("mesh{}", m)),
                           .first_vertex = offset,
                           .vertices = static_cast<Eigen::Index>(nv)});
      if (rigid_joint >= 0)
        out.notes.push_back(fmt::format("mesh \"{}\" has no bones: it follows joint \"{}\" rigidly", out.parts.back().name,
                                        one_line(out.skeleton.joints[static_cast<std::size_t>(rigid_joint)].name)));
    }
    // A joint without a node rests where its bone was bound.
    for (std::size_t j = 0; j < joints; ++j)
      if (joint_node_[j] < 0) {
        const Eigen::Matrix4d bind = out.inverse_bind[j].inverse();
        if (const std::string why = rig_build::decompose(bind, out.skeleton.joints[j].rest); !why.empty())
          fail(fmt::format("bone \"{}\" (in no node): its bind frame {}", one_line(out.skeleton.joints[j].name), why));
      }
    // Joints no bone names (animated ancestors, a bone without weights): bound at their rest frame.
    const std::vector<Eigen::Affine3d> world = rest_world(out);
    for (std::size_t j = 0; j < joints; ++j)
      if (bound_by[j] < 0) out.inverse_bind[j] = world[j].matrix().inverse();
    data.store(out);
  }

  /// Keys of one path as a channel: times in seconds, strictly increasing (keys at one time: the last kept).
  template <class Key, class Value>
  void add_channel(Clip& clip, int joint, const std::string& joint_name, ChannelPath path, const Key* keys, unsigned count, double ticks, const std::string& where,
                   Value value) const {
    if (count == 0) return;
    std::vector<unsigned> order(count);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](unsigned a, unsigned b) { return keys[a].mTime < keys[b].mTime; });
    Channel c;
    c.joint = joint;
    c.path = path;
    c.interpolation = Interpolation::linear;
    std::vector<Eigen::Vector4d> values;
    for (const unsigned k : order) {
      const double t = keys[k].mTime / ticks;
      if (!std::isfinite(t)) fail(fmt::format("{}: key {} has a time that is not finite", where, k));
      const Eigen::Vector4d v = value(keys[k].mValue);
      if (!v.allFinite()) fail(fmt::format("{}: key {} has a value that is not finite", where, k));
      if (!c.times.empty() && !(t > c.times.back())) {
        values.back() = v;
        continue;
      }
      c.times.push_back(t);
      values.push_back(v);
    }
    const int rows = path == ChannelPath::rotation ? 4 : 3;
    c.values.resize(rows, static_cast<Eigen::Index>(values.size()));
    for (std::size_t k = 0; k < values.size(); ++k)
      for (int r = 0; r < rows; ++r) c.values(r, static_cast<Eigen::Index>(k)) = values[k](r);
    if (between_[static_cast<std::size_t>(joint)] != Eigen::Matrix4d::Identity())
      rig_build::fold_in(path_, between_[static_cast<std::size_t>(joint)], c, joint_name);
    clip.channels.push_back(std::move(c));
  }

  void read_animations(RiggedModel& out) {
    for (unsigned a = 0; a < s_.mNumAnimations; ++a) {
      const aiAnimation* anim = s_.mAnimations[a];
      Clip clip;
      clip.name = name_of(anim->mName);
      if (clip.name.empty()) clip.name = fmt::format("animation{}", a);
      const bool timed = anim->mTicksPerSecond > 0.0 && std::isfinite(anim->mTicksPerSecond);
      const double ticks = timed ? anim->mTicksPerSecond : 25.0;
      if (!timed) out.notes.push_back(fmt::format("animation \"{}\" gives no ticks per second: 25 assumed", one_line(clip.name)));
      for (unsigned ci = 0; ci < anim->mNumChannels; ++ci) {
        const aiNodeAnim* ch = anim->mChannels[ci];
        const auto it = by_name_.find(name_of(ch->mNodeName));
        if (it == by_name_.end()) continue;
        const int joint = joint_of_node_[static_cast<std::size_t>(it->second)];
        if (joint < 0) continue;  // a node that moves no vertex
        const std::string& name = out.skeleton.joints[static_cast<std::size_t>(joint)].name;
        const std::string where = fmt::format("animation \"{}\" channel of \"{}\"", one_line(clip.name), one_line(name));
        const auto vec = [](const aiVector3D& v) { return Eigen::Vector4d(v.x, v.y, v.z, 0.0); };
        add_channel(clip, joint, name, ChannelPath::translation, ch->mPositionKeys, ch->mNumPositionKeys, ticks, where + " (translation)", vec);
        add_channel(clip, joint, name, ChannelPath::rotation, ch->mRotationKeys, ch->mNumRotationKeys, ticks, where + " (rotation)",
                    [&](const aiQuaternion& q) {
                      const Eigen::Vector4d v(q.x, q.y, q.z, q.w);  // x, y, z, w as a rotation channel stores it
                      const double len = v.norm();
                      if (!(len > 1e-6)) fail(fmt::format("{} (rotation): a quaternion of length {}", where, len));
                      return Eigen::Vector4d(v / len);
                    });
        add_channel(clip, joint, name, ChannelPath::scale, ch->mScalingKeys, ch->mNumScalingKeys, ticks, where + " (scale)", vec);
      }
      out.clips.push_back(std::move(clip));
    }
  }

  const fs::path& path_;
  const aiScene& s_;
  std::vector<const aiNode*> nodes_;      ///< depth first from the root
  std::vector<int> parent_;               ///< per node
  std::vector<Eigen::Matrix4d> global_;   ///< per node: to the root's space, at rest
  std::map<std::string, int> by_name_;    ///< the first node of each name
  std::vector<std::pair<int, unsigned>> meshes_;  ///< skinned meshes: (node, mesh)
  std::vector<std::pair<int, unsigned>> rigid_;   ///< meshes without bones: (node, mesh), read where a joint is above them
  std::vector<int> joint_of_node_;        ///< per node: its joint, or −1
  std::vector<int> joint_node_;           ///< per joint: its node (−1 for a bone in no node)
  std::map<std::string, int> nodeless_;   ///< bones in no node: their joints
  std::vector<Eigen::Matrix4d> between_;  ///< per joint: the nodes' transforms folded into its rest transform
};

}  // namespace

RiggedModel read_assimp(const std::filesystem::path& path) {
  (void)rig_build::check_file(path, "model");
  Assimp::Importer importer;
  importer.SetPropertyBool(AI_CONFIG_IMPORT_FBX_PRESERVE_PIVOTS, false);  // no helper nodes between a joint and its parent
  importer.SetPropertyInteger(AI_CONFIG_PP_LBW_MAX_WEIGHTS, 4);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_JoinIdenticalVertices |
                         aiProcess_LimitBoneWeights | aiProcess_ValidateDataStructure;
  const aiScene* scene = nullptr;
  try {
    scene = importer.ReadFile(path.string(), flags);
  } catch (const std::exception& e) {
    rig_build::fail(path, fmt::format("assimp could not read it: {}", one_line(e.what())));
  }
  if (scene == nullptr) {
    std::string why = one_line(importer.GetErrorString());
    if (why.empty()) why = "no reason given";
    rig_build::fail(path, fmt::format("assimp could not read it: {}", why));
  }
  std::string format = "assimp";
  const std::string ext = path.extension().string();
  if (!ext.empty()) {
    const std::size_t i = importer.GetImporterIndex(ext.c_str());
    if (const aiImporterDesc* desc = importer.GetImporterInfo(i); desc != nullptr && desc->mName != nullptr)
      format = fmt::format("{} (assimp {}.{}.{})", strip_importer(one_line(desc->mName)), aiGetVersionMajor(), aiGetVersionMinor(), aiGetVersionPatch());
  }
  return SceneReader(path, *scene).build(format);
}

}  // namespace snh
