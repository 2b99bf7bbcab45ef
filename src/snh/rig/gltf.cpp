#include "snh/rig/gltf.hpp"

#include "snh/rig/gltf_load.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <string_view>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <fmt/format.h>

#include "snh/rig/model_build.hpp"

namespace snh {
namespace {

namespace fs = std::filesystem;
using rig_build::check_file;
using rig_build::decompose;
using rig_build::fail;
using rig_build::max_coordinate;
using rig_build::one_line;
static_assert(std::endian::native == std::endian::little, "glTF buffers are little-endian; this reader copies them as is");

int type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

std::string type_name(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return fmt::format("type {}", type);
  }
}

int component_bytes(int component) {
  switch (component) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

std::string component_name(int component) {
  switch (component) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: return "byte";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return "unsigned byte";
    case TINYGLTF_COMPONENT_TYPE_SHORT: return "short";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return "unsigned short";
    case TINYGLTF_COMPONENT_TYPE_INT: return "int";
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: return "unsigned int";
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return "float";
    default: return fmt::format("component type {}", component);
  }
}

/// One component at p as a double; integers mapped to [0, 1] or [−1, 1] when `normalize` (glTF 2.0 §3.11).
double component(const unsigned char* p, int type, bool normalize) {
  switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
      const auto v = static_cast<std::int8_t>(p[0]);
      return normalize ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalize ? p[0] / 255.0 : p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return normalize ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
      std::uint16_t v;
      std::memcpy(&v, p, 2);
      return normalize ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
      std::uint32_t v;
      std::memcpy(&v, p, 4);
      return normalize ? v / 4294967295.0 : v;
    }
    default: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
  }
}

/// The 25 joints of the WebXR Hand Input API and the parent of each (by name; "" for the wrist).
const std::vector<std::pair<std::string, std::string>>& webxr_hand_joints() {
  static const std::vector<std::pair<std::string, std::string>> joints = [] {
    std::vector<std::pair<std::string, std::string>> j{{"wrist", ""}};
    const auto chain = [&](const std::string& finger, std::vector<std::string> bones) {
      std::string parent = "wrist";
      for (const std::string& b : bones) {
        j.emplace_back(finger + "-" + b, parent);
        parent = finger + "-" + b;
      }
    };
    chain("thumb", {"metacarpal", "phalanx-proximal", "phalanx-distal", "tip"});
    for (const char* f : {"index-finger", "middle-finger", "ring-finger", "pinky-finger"})
      chain(f, {"metacarpal", "phalanx-proximal", "phalanx-intermediate", "phalanx-distal", "tip"});
    return j;
  }();
  return joints;
}

/// Reads one tinygltf model into a RiggedModel; every fault is a RigError naming the file.
class Builder {
 public:
  Builder(const fs::path& path, const tinygltf::Model& m) : path_(path), m_(m) {}

  RiggedModel build() {
    RiggedModel out;
    out.source = path_;
    out.format = "glTF 2.0";
    check_asset();
    link_nodes();
    const std::vector<int> nodes = skinned_nodes();
    const int skin = m_.nodes[static_cast<std::size_t>(nodes.front())].skin;
    for (const int node : nodes) {
      const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(node)];
      if (n.skin < 0 || n.skin >= static_cast<int>(m_.skins.size()))
        fail(fmt::format("node {} refers to skin {}, which does not exist", node_name(node), n.skin));
      if (n.mesh < 0 || n.mesh >= static_cast<int>(m_.meshes.size()))
        fail(fmt::format("node {} refers to mesh {}, which does not exist", node_name(node), n.mesh));
    }
    read_skin(m_.skins[static_cast<std::size_t>(skin)], skin, out);
    // Every skinned mesh of the first one's skin, in the scene's order (a mesh that two nodes show, once); a
    // mesh of another skin is named in `skipped`.
    rig_build::SkinData data;
    std::vector<int> read;
    for (const int node : nodes) {
      const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(node)];
      const std::string name = n.name.empty() ? fmt::format("mesh{}", n.mesh) : one_line(n.name);
      if (n.skin != skin) {
        out.skipped.push_back(name);
        continue;
      }
      if (std::find(read.begin(), read.end(), n.mesh) != read.end()) continue;
      read.push_back(n.mesh);
      const auto first = static_cast<Eigen::Index>(data.xyz.size());
      read_mesh(n.mesh, out.skeleton.size(), data);
      out.parts.push_back({.name = name, .first_vertex = first, .vertices = static_cast<Eigen::Index>(data.xyz.size()) - first});
    }
    // Meshes without a skin that hang under a joint (eyes, teeth, props parented to a bone) follow it rigidly.
    for (const int node : rigid_nodes()) {
      const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(node)];
      if (n.mesh >= static_cast<int>(m_.meshes.size()))
        fail(fmt::format("node {} refers to mesh {}, which does not exist", node_name(node), n.mesh));
      int joint = joint_of_node_[static_cast<std::size_t>(node)];
      Eigen::Matrix4d chain = node_transform(node).matrix().matrix();
      if (joint >= 0) {
        chain.setIdentity();
      } else {
        const auto [between, above] =
            rig_build::joint_above(node, parent_, joint_of_node_, [&](int p) { return Eigen::Matrix4d(node_transform(p).matrix().matrix()); });
        joint = above;
        chain = between * chain;
      }
      if (joint < 0) continue;
      const std::string name = n.name.empty() ? fmt::format("mesh{}", n.mesh) : one_line(n.name);
      const Eigen::Matrix4d place = out.inverse_bind[static_cast<std::size_t>(joint)].inverse() * chain;
      const auto first = static_cast<Eigen::Index>(data.xyz.size());
      read_mesh(n.mesh, out.skeleton.size(), data, joint, place);
      out.parts.push_back({.name = name, .first_vertex = first, .vertices = static_cast<Eigen::Index>(data.xyz.size()) - first});
      out.notes.push_back(fmt::format("mesh \"{}\" has no skin: it follows joint \"{}\" rigidly", name,
                                      one_line(out.skeleton.joints[static_cast<std::size_t>(joint)].name)));
    }
    data.store(out);
    rig_build::weld(out);
    read_animations(out);
    if (all_roots(out.skeleton) && !animated_) rebuild_from_names(out);
    rig_build::check_rest(out);
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { rig_build::fail(path_, what); }

  std::string node_name(int i) const {
    const std::string& name = m_.nodes[static_cast<std::size_t>(i)].name;
    return name.empty() ? fmt::format("{}", i) : fmt::format("{} \"{}\"", i, one_line(name));
  }

  /// The parent of every node, checking that the children links form a forest.
  void link_nodes() {
    const int n = static_cast<int>(m_.nodes.size());
    parent_.assign(m_.nodes.size(), -1);
    for (int i = 0; i < n; ++i)
      for (const int c : m_.nodes[static_cast<std::size_t>(i)].children) {
        if (c < 0 || c >= n) fail(fmt::format("node {} has child {}, which does not exist", node_name(i), c));
        if (parent_[static_cast<std::size_t>(c)] >= 0)
          fail(fmt::format("node {} is a child of two nodes ({} and {})", c, parent_[static_cast<std::size_t>(c)], i));
        parent_[static_cast<std::size_t>(c)] = i;
      }
    std::vector<char> state(m_.nodes.size(), 0);  // 0 unseen, 1 on the current walk, 2 reaches a root
    for (int i = 0; i < n; ++i) {
      std::vector<int> walk;
      int j = i;
      while (j >= 0 && state[static_cast<std::size_t>(j)] == 0) {
        state[static_cast<std::size_t>(j)] = 1;
        walk.push_back(j);
        j = parent_[static_cast<std::size_t>(j)];
      }
      if (j >= 0 && state[static_cast<std::size_t>(j)] == 1) fail(fmt::format("the node hierarchy has a cycle through node {}", j));
      for (const int k : walk) state[static_cast<std::size_t>(k)] = 2;
    }
  }

  /// The nodes with a mesh, depth first through the default scene (scene 0 if none is named; every root node
  /// if the file has no scene), each once.
  std::vector<int> mesh_nodes() const {
    std::vector<int> roots;
    if (!m_.scenes.empty()) {
      const int s = m_.defaultScene >= 0 && m_.defaultScene < static_cast<int>(m_.scenes.size()) ? m_.defaultScene : 0;
      roots = m_.scenes[static_cast<std::size_t>(s)].nodes;
    } else {
      for (int i = 0; i < static_cast<int>(m_.nodes.size()); ++i)
        if (parent_[static_cast<std::size_t>(i)] < 0) roots.push_back(i);
    }
    std::vector<int> stack(roots.rbegin(), roots.rend()), found;
    std::vector<char> seen(m_.nodes.size(), 0);
    while (!stack.empty()) {
      const int i = stack.back();
      stack.pop_back();
      if (i < 0 || i >= static_cast<int>(m_.nodes.size())) fail(fmt::format("the scene refers to node {}, which does not exist", i));
      if (seen[static_cast<std::size_t>(i)]) continue;  // a scene listing a node twice
      seen[static_cast<std::size_t>(i)] = 1;
      const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(i)];
      if (n.mesh >= 0) found.push_back(i);
      stack.insert(stack.end(), n.children.rbegin(), n.children.rend());
    }
    return found;
  }

  /// The nodes with a mesh and a skin, in the scene's order.
  std::vector<int> skinned_nodes() const {
    std::vector<int> found;
    for (const int i : mesh_nodes())
      if (m_.nodes[static_cast<std::size_t>(i)].skin >= 0) found.push_back(i);
    if (found.empty()) fail("no skinned mesh (a mesh node with a skin)");
    return found;
  }

  /// The nodes with a mesh and no skin, in the scene's order.
  std::vector<int> rigid_nodes() const {
    std::vector<int> found;
    for (const int i : mesh_nodes())
      if (m_.nodes[static_cast<std::size_t>(i)].skin < 0) found.push_back(i);
    return found;
  }

  /// A node's local transform as TRS (from its matrix if it has one).
  Transform node_transform(int i) const {
    const tinygltf::Node& n = m_.nodes[static_cast<std::size_t>(i)];
    Transform t;
    if (!n.matrix.empty()) {
      if (n.matrix.size() != 16) fail(fmt::format("node {} has a matrix of {} numbers, not 16", node_name(i), n.matrix.size()));
      const Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix4d>(n.matrix.data());  // column-major, as glTF stores it
      if (const std::string why = decompose(m, t); !why.empty()) fail(fmt::format("the matrix of node {} {}", node_name(i), why));
      return t;
    }
    const auto vec = [&](const std::vector<double>& v, std::size_t size, const char* what) {
      if (v.size() != size) fail(fmt::format("node {} has a {} of {} numbers, not {}", node_name(i), what, v.size(), size));
      for (const double x : v) {
        if (!std::isfinite(x)) fail(fmt::format("node {} has a {} that is not finite", node_name(i), what));
        if (std::abs(x) > max_coordinate)
          fail(fmt::format("node {} has a {} of {:g}, beyond {:g}", node_name(i), what, x, max_coordinate));
      }
    };
    if (!n.translation.empty()) {
      vec(n.translation, 3, "translation");
      t.translation = Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]);
    }
    if (!n.rotation.empty()) {
      vec(n.rotation, 4, "rotation");
      const Eigen::Quaterniond q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
      if (!(q.norm() > 1e-6)) fail(fmt::format("node {} has a rotation quaternion of length {}", node_name(i), q.norm()));
      t.rotation = q.normalized();
    }
    if (!n.scale.empty()) {
      vec(n.scale, 3, "scale");
      t.scale = Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]);
    }
    return t;
  }

  /// What the whole file declares: glTF 2.x, extensions it cannot be read without that snh knows to ignore
  /// (materials, textures and lights change no vertex), and a default scene that exists.
  void check_asset() const {
    if (m_.asset.version.rfind("2.", 0) != 0)
      fail(fmt::format("asset version \"{}\": snh reads glTF 2.0", one_line(m_.asset.version)));
    for (const std::string& e : m_.extensionsRequired) {
      const bool harmless = e.rfind("KHR_materials_", 0) == 0 || e.rfind("KHR_texture_", 0) == 0 ||
                            e.rfind("EXT_texture_", 0) == 0 || e == "KHR_lights_punctual";
      if (!harmless) fail(fmt::format("the file requires the extension {}, which snh does not read", one_line(e)));
    }
    if (m_.defaultScene >= static_cast<int>(m_.scenes.size()))
      fail(fmt::format("its scene is {}, but it has {} scenes", m_.defaultScene, m_.scenes.size()));
  }

  Transform decomposed(const Eigen::Matrix4d& m, const std::string& what) const {
    Transform t;
    if (const std::string why = decompose(m, t); !why.empty()) fail(fmt::format("{} {}", what, why));
    return t;
  }

  void read_skin(const tinygltf::Skin& skin, int skin_index, RiggedModel& out) {
    const int nodes = static_cast<int>(m_.nodes.size());
    const int joints = static_cast<int>(skin.joints.size());
    if (joints == 0) fail(fmt::format("skin {} has no joints", skin_index));
    joint_of_node_.assign(m_.nodes.size(), -1);
    for (int j = 0; j < joints; ++j) {
      const int node = skin.joints[static_cast<std::size_t>(j)];
      if (node < 0 || node >= nodes) fail(fmt::format("joint {} of skin {} is node {}, which does not exist", j, skin_index, node));
      if (joint_of_node_[static_cast<std::size_t>(node)] >= 0)
        fail(fmt::format("node {} appears twice among the joints of skin {}", node_name(node), skin_index));
      joint_of_node_[static_cast<std::size_t>(node)] = j;
    }
    out.skeleton.joints.resize(static_cast<std::size_t>(joints));
    between_.clear();
    for (int j = 0; j < joints; ++j) {
      const int node = skin.joints[static_cast<std::size_t>(j)];
      Joint& joint = out.skeleton.joints[static_cast<std::size_t>(j)];
      const std::string& name = m_.nodes[static_cast<std::size_t>(node)].name;
      joint.name = name.empty() ? fmt::format("joint{}", j) : name;
      // Nodes between the joint and its nearest joint ancestor (or the scene root) fold into its rest transform.
      const auto [between, above] =
          rig_build::joint_above(node, parent_, joint_of_node_, [&](int p) { return Eigen::Matrix4d(node_transform(p).matrix().matrix()); });
      joint.parent = above;
      joint.rest = node_transform(node);
      between_.push_back(between);
      if (between != Eigen::Matrix4d::Identity())
        joint.rest = decomposed(between * joint.rest.matrix().matrix(),
                                fmt::format("the rest transform of joint {} (its ancestors' transforms folded in)", node_name(node)));
    }
    out.inverse_bind.assign(static_cast<std::size_t>(joints), Eigen::Matrix4d::Identity());
    if (skin.inverseBindMatrices >= 0) {
      const Eigen::MatrixXd ib = accessor(skin.inverseBindMatrices, fmt::format("the inverse bind matrices of skin {}", skin_index),
                                          TINYGLTF_TYPE_MAT4, {TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
      if (ib.cols() < joints)
        fail(fmt::format("skin {} has {} joints but {} inverse bind matrices", skin_index, joints, ib.cols()));
      if (!ib.allFinite()) fail(fmt::format("an inverse bind matrix of skin {} is not finite", skin_index));
      for (int j = 0; j < joints; ++j) {
        const Eigen::Matrix4d m = Eigen::Map<const Eigen::Matrix4d>(ib.col(j).data());
        // An affine map that can be undone and moves no point beyond the coordinates snh takes: a zero,
        // singular, vanishing (1e-30) or projective matrix would put the skin nowhere.
        const Eigen::Vector3d s = Eigen::JacobiSVD<Eigen::Matrix3d>(m.topLeftCorner<3, 3>()).singularValues();
        std::string why;
        if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-6)) why = "is projective (its last row is not 0 0 0 1)";
        else if (!(s[0] >= 1e-9 && s[0] <= 1e9) || !(s[2] > 1e-9 * s[0])) why = fmt::format("is singular or scales by {:g} to {:g}", s[2], s[0]);
        else if (m.topRightCorner<3, 1>().cwiseAbs().maxCoeff() > max_coordinate) why = "translates beyond 1e12";
        if (!why.empty())
          fail(fmt::format("the inverse bind matrix of joint {} (skin {}) {}", node_name(skin.joints[static_cast<std::size_t>(j)]),
                           skin_index, why));
        out.inverse_bind[static_cast<std::size_t>(j)] = m;
      }
    }
  }

  /// An accessor's elements, one column each (components in rows), bounds-checked against its buffer view and
  /// buffer. `components`: the component types allowed; integers are normalized when `normalize`.
  Eigen::MatrixXd accessor(int index, const std::string& what, int type, std::initializer_list<int> components,
                           bool normalize) const {
    if (index < 0 || index >= static_cast<int>(m_.accessors.size()))
      fail(fmt::format("{}: accessor {} does not exist", what, index));
    const tinygltf::Accessor& a = m_.accessors[static_cast<std::size_t>(index)];
    const std::string where = fmt::format("{} (accessor {})", what, index);
    if (a.type != type) fail(fmt::format("{}: {} where {} is expected", where, type_name(a.type), type_name(type)));
    if (std::find(components.begin(), components.end(), a.componentType) == components.end())
      fail(fmt::format("{}: components of type {} are not supported here", where, component_name(a.componentType)));
    if (a.sparse.isSparse) fail(fmt::format("{}: sparse accessors are not supported", where));
    if (a.count == 0) fail(fmt::format("{}: no elements", where));
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(m_.bufferViews.size()))
      fail(fmt::format("{}: buffer view {} does not exist", where, a.bufferView));
    const tinygltf::BufferView& v = m_.bufferViews[static_cast<std::size_t>(a.bufferView)];
    if (v.buffer < 0 || v.buffer >= static_cast<int>(m_.buffers.size()))
      fail(fmt::format("{}: buffer view {} refers to buffer {}, which does not exist", where, a.bufferView, v.buffer));
    const std::vector<unsigned char>& data = m_.buffers[static_cast<std::size_t>(v.buffer)].data;
    if (v.byteOffset > data.size() || v.byteLength > data.size() - v.byteOffset)
      fail(fmt::format("{}: buffer view {} (bytes {} to {}) lies outside buffer {} of {} bytes", where, a.bufferView,
                       v.byteOffset, v.byteOffset + v.byteLength, v.buffer, data.size()));
    const int comps = type_components(a.type);
    const std::size_t bytes = static_cast<std::size_t>(component_bytes(a.componentType));
    const std::size_t element = static_cast<std::size_t>(comps) * bytes;
    const std::size_t stride = v.byteStride == 0 ? element : v.byteStride;
    if (stride < element) fail(fmt::format("{}: a byte stride of {} for elements of {} bytes", where, stride, element));
    // The last element must end inside the view: byteOffset + (count − 1) · stride + element ≤ byteLength.
    if (a.byteOffset > v.byteLength || element > v.byteLength - a.byteOffset ||
        a.count - 1 > (v.byteLength - a.byteOffset - element) / stride)
      fail(fmt::format("{}: {} elements of {} bytes (stride {}) from byte {} overrun buffer view {} of {} bytes", where, a.count,
                       element, stride, a.byteOffset, a.bufferView, v.byteLength));
    const unsigned char* base = data.data() + v.byteOffset + a.byteOffset;
    Eigen::MatrixXd out(comps, static_cast<Eigen::Index>(a.count));
    for (std::size_t i = 0; i < a.count; ++i)
      for (int c = 0; c < comps; ++c)
        out(c, static_cast<Eigen::Index>(i)) =
            component(base + i * stride + static_cast<std::size_t>(c) * bytes, a.componentType, normalize);
    return out;
  }

  /// Appends a mesh's triangle primitives to `data`.
  /// Appends a mesh's primitives to `data`; a rigid mesh (rigid_joint ≥ 0: no skin of its own) is placed by
  /// `place` (its vertices into the model at the bind pose) and bound wholly to that joint.
  void read_mesh(int mesh_index, int joints, rig_build::SkinData& data, int rigid_joint = -1,
                 const Eigen::Matrix4d& place = Eigen::Matrix4d::Identity()) const {
    const tinygltf::Mesh& mesh = m_.meshes[static_cast<std::size_t>(mesh_index)];
    if (mesh.primitives.empty()) fail(fmt::format("mesh {} has no primitives", mesh_index));
    auto& xyz = data.xyz;
    auto& jidx = data.jidx;
    auto& jw = data.jw;
    auto& tri = data.tri;
    const std::size_t triangles_before = tri.size();
    for (std::size_t p = 0; p < mesh.primitives.size(); ++p) {
      const tinygltf::Primitive& prim = mesh.primitives[p];
      const std::string where = fmt::format("mesh {} primitive {}", mesh_index, p);
      if (prim.mode != TINYGLTF_MODE_TRIANGLES)
        fail(fmt::format("{}: mode {} is not triangles (4); only triangle lists are supported", where, prim.mode));
      const auto attribute = [&](const char* name) {
        const auto it = prim.attributes.find(name);
        if (it == prim.attributes.end()) fail(fmt::format("{}: no {} attribute", where, name));
        return it->second;
      };
      const Eigen::MatrixXd pos = accessor(attribute("POSITION"), where + " POSITION", TINYGLTF_TYPE_VEC3,
                                           {TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
      const Eigen::Index n = pos.cols();
      const bool rigid = rigid_joint >= 0;
      const std::initializer_list<int> weight_types{TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                                    TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};
      Eigen::MatrixXd jnt = Eigen::MatrixXd::Zero(4, n), wgt = Eigen::MatrixXd::Zero(4, n);
      if (rigid) {
        jnt.row(0).setConstant(rigid_joint);
        wgt.row(0).setOnes();
      } else {
        jnt = accessor(attribute("JOINTS_0"), where + " JOINTS_0", TINYGLTF_TYPE_VEC4,
                       {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT}, false);
        wgt = accessor(attribute("WEIGHTS_0"), where + " WEIGHTS_0", TINYGLTF_TYPE_VEC4, weight_types, true);
      }
      if (jnt.cols() != n || wgt.cols() != n)
        fail(fmt::format("{}: {} positions, {} JOINTS_0 and {} WEIGHTS_0", where, n, jnt.cols(), wgt.cols()));
      if (const auto it = prim.attributes.find("WEIGHTS_1"); it != prim.attributes.end()) {
        const Eigen::MatrixXd more = accessor(it->second, where + " WEIGHTS_1", TINYGLTF_TYPE_VEC4, weight_types, true);
        for (Eigen::Index v = 0; v < more.cols(); ++v)
          if (!(more.col(v).cwiseAbs().maxCoeff() == 0.0))
            fail(fmt::format("{}: vertex {} has more than 4 joint influences (WEIGHTS_1), which is not supported", where, v));
      }
      if (xyz.size() + static_cast<std::size_t>(n) > static_cast<std::size_t>(std::numeric_limits<int>::max() / 4))
        fail(fmt::format("{}: too many vertices", where));
      // Texture coordinates and normals where the primitive has them (glTF's v runs down the image: flipped).
      const auto optional = [&](const char* name, int type, std::initializer_list<int> kinds, bool normalize) {
        const auto it = prim.attributes.find(name);
        Eigen::MatrixXd m;
        if (it != prim.attributes.end()) m = accessor(it->second, where + " " + name, type, kinds, normalize);
        if (m.size() > 0 && (m.cols() != n || !m.allFinite())) m.resize(0, 0);  // unusable: left out, as if absent
        return m;
      };
      const Eigen::MatrixXd st = optional("TEXCOORD_0", TINYGLTF_TYPE_VEC2,
                                          {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                           TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                                          true);
      const Eigen::MatrixXd nrm = optional("NORMAL", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
      data.all_uv = data.all_uv && st.size() > 0;
      data.all_normals = data.all_normals && nrm.size() > 0;
      for (Eigen::Index v = 0; data.all_uv && v < n; ++v) data.uv.emplace_back(st(0, v), 1.0 - st(1, v));
      const Eigen::Matrix3d normal_map = place.topLeftCorner<3, 3>().inverse().transpose();
      for (Eigen::Index v = 0; data.all_normals && v < n; ++v)
        data.normal.emplace_back(rigid ? Eigen::Vector3d((normal_map * nrm.col(v)).normalized()) : Eigen::Vector3d(nrm.col(v)));
      const int offset = static_cast<int>(xyz.size());
      for (Eigen::Index v = 0; v < n; ++v) {
        if (!pos.col(v).allFinite()) fail(fmt::format("{}: vertex {} has a position that is not finite", where, v));
        if (pos.col(v).cwiseAbs().maxCoeff() > max_coordinate)
          fail(fmt::format("{}: vertex {} has a coordinate of {:g}, beyond {:g}", where, v, pos.col(v).cwiseAbs().maxCoeff(),
                           max_coordinate));
        Eigen::Vector4d w = wgt.col(v);
        if (!w.allFinite() || w.minCoeff() < 0.0)
          fail(fmt::format("{}: vertex {} has joint weights {} {} {} {} (each must be finite and at least 0)", where, v, w(0), w(1),
                           w(2), w(3)));
        const double sum = w.sum();
        if (!(sum > 0.0)) fail(fmt::format("{}: vertex {} has joint weights that are all zero", where, v));
        Eigen::Vector4i j;
        for (int k = 0; k < 4; ++k) {
          const double jk = jnt(k, v);
          if (jk >= joints)
            fail(fmt::format("{}: vertex {} is bound to joint {}, but the skin has {} joints", where, v,
                             static_cast<long long>(jk), joints));
          j(k) = static_cast<int>(jk);
        }
        xyz.emplace_back(rigid ? Eigen::Vector3d(place.topLeftCorner<3, 3>() * pos.col(v) + place.topRightCorner<3, 1>())
                               : Eigen::Vector3d(pos.col(v)));
        jidx.push_back(j);
        jw.emplace_back(w / sum);
      }
      if (prim.indices >= 0) {
        const Eigen::MatrixXd idx = accessor(prim.indices, where + " indices", TINYGLTF_TYPE_SCALAR,
                                             {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                              TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                                             false);
        if (idx.cols() % 3 != 0) fail(fmt::format("{}: {} indices, not a multiple of 3", where, idx.cols()));
        for (Eigen::Index i = 0; i < idx.cols(); ++i)
          if (idx(0, i) >= static_cast<double>(n))
            fail(fmt::format("{}: index {} refers to vertex {}, but the primitive has {} vertices", where, i,
                             static_cast<long long>(idx(0, i)), n));
        for (Eigen::Index t = 0; t < idx.cols() / 3; ++t)
          tri.emplace_back(offset + static_cast<int>(idx(0, 3 * t)), offset + static_cast<int>(idx(0, 3 * t + 1)),
                           offset + static_cast<int>(idx(0, 3 * t + 2)));
      } else {
        if (n % 3 != 0) fail(fmt::format("{}: {} vertices without indices, not a multiple of 3", where, n));
        for (int t = 0; t < static_cast<int>(n / 3); ++t) tri.emplace_back(offset + 3 * t, offset + 3 * t + 1, offset + 3 * t + 2);
      }
    }
    if (tri.size() == triangles_before) fail(fmt::format("mesh {} has no triangles", mesh_index));
  }

  void read_animations(RiggedModel& out) {
    for (std::size_t ai = 0; ai < m_.animations.size(); ++ai) {
      const tinygltf::Animation& anim = m_.animations[ai];
      Clip clip;
      clip.name = anim.name.empty() ? fmt::format("animation{}", ai) : anim.name;
      const std::string label =
          anim.name.empty() ? fmt::format("animation {}", ai) : fmt::format("animation {} \"{}\"", ai, one_line(anim.name));
      for (std::size_t ci = 0; ci < anim.channels.size(); ++ci) {
        const tinygltf::AnimationChannel& ch = anim.channels[ci];
        const std::string where = fmt::format("{} channel {}", label, ci);
        ChannelPath path;
        if (ch.target_path == "translation") path = ChannelPath::translation;
        else if (ch.target_path == "rotation") path = ChannelPath::rotation;
        else if (ch.target_path == "scale") path = ChannelPath::scale;
        else continue;  // morph target weights (or an extension's path): not a joint's transform
        if (ch.target_node < 0) continue;  // no node: animated by an extension
        if (ch.target_node >= static_cast<int>(m_.nodes.size()))
          fail(fmt::format("{}: targets node {}, which does not exist", where, ch.target_node));
        const int joint = joint_of_node_[static_cast<std::size_t>(ch.target_node)];
        if (joint < 0) continue;  // a node that is not one of the skin's joints
        if (ch.sampler < 0 || ch.sampler >= static_cast<int>(anim.samplers.size()))
          fail(fmt::format("{}: sampler {} does not exist", where, ch.sampler));
        const tinygltf::AnimationSampler& s = anim.samplers[static_cast<std::size_t>(ch.sampler)];
        const std::string sw = fmt::format("{} sampler {}", label, ch.sampler);
        Channel c;
        c.joint = joint;
        c.path = path;
        if (s.interpolation.empty() || s.interpolation == "LINEAR") c.interpolation = Interpolation::linear;
        else if (s.interpolation == "STEP") c.interpolation = Interpolation::step;
        else if (s.interpolation == "CUBICSPLINE") c.interpolation = Interpolation::cubic_spline;
        else fail(fmt::format("{}: unknown interpolation \"{}\"", sw, one_line(s.interpolation)));
        const Eigen::MatrixXd in = accessor(s.input, sw + " input", TINYGLTF_TYPE_SCALAR, {TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
        c.times.assign(in.data(), in.data() + in.size());
        for (std::size_t k = 0; k < c.times.size(); ++k) {
          if (!std::isfinite(c.times[k])) fail(fmt::format("{}: key time {} is not finite", sw, k));
          if (c.times[k] < 0.0) fail(fmt::format("{}: key time {} is negative ({:g}; glTF times start at 0)", sw, k, c.times[k]));
          if (k > 0 && !(c.times[k] > c.times[k - 1]))
            fail(fmt::format("{}: key times are not strictly increasing ({} then {})", sw, c.times[k - 1], c.times[k]));
        }
        const bool rotation = path == ChannelPath::rotation;
        const Eigen::MatrixXd values =
            rotation ? accessor(s.output, sw + " output", TINYGLTF_TYPE_VEC4,
                                {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                 TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                                true)
                     : accessor(s.output, sw + " output", TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, false);
        const std::size_t per_key = c.interpolation == Interpolation::cubic_spline ? 3 : 1;
        if (static_cast<std::size_t>(values.cols()) != per_key * c.times.size())
          fail(fmt::format("{}: {} key times but {} output values{}", sw, c.times.size(), values.cols(),
                           per_key == 3 ? " (CUBICSPLINE needs 3 per key)" : ""));
        if (!values.allFinite()) fail(fmt::format("{}: an output value is not finite", sw));
        c.values = values;
        if (rotation)
          for (std::size_t k = 0; k < c.times.size(); ++k) {
            const auto col = static_cast<Eigen::Index>(per_key == 3 ? 3 * k + 1 : k);
            const double len = c.values.col(col).norm();
            if (!(len > 1e-6)) fail(fmt::format("{}: key {} is a rotation quaternion of length {}", sw, k, len));
            if (per_key == 1) c.values.col(col) /= len;
          }
        if (between_[static_cast<std::size_t>(joint)] != Eigen::Matrix4d::Identity())
          rig_build::fold_in(path_, between_[static_cast<std::size_t>(joint)], c, out.skeleton.joints[static_cast<std::size_t>(joint)].name);
        clip.channels.push_back(std::move(c));
        animated_ = true;
      }
      out.clips.push_back(std::move(clip));
    }
  }

  static bool all_roots(const Skeleton& s) {
    return std::all_of(s.joints.begin(), s.joints.end(), [](const Joint& j) { return j.parent < 0; });
  }

  /// A skin whose joints are all roots and named exactly as the WebXR Hand Input joints: the chain rebuilt from
  /// the names, every joint's world rest transform kept.
  void rebuild_from_names(RiggedModel& out) const {
    Skeleton& s = out.skeleton;
    const auto& hand = webxr_hand_joints();
    if (s.joints.size() != hand.size()) return;
    for (const auto& [name, parent] : hand)
      if (s.find(name) < 0) return;  // with 25 distinct names found among 25 joints, the names match exactly
    std::vector<Eigen::Affine3d> world;
    for (const Joint& j : s.joints) world.push_back(j.rest.matrix());
    for (const auto& [name, parent] : hand)
      s.joints[static_cast<std::size_t>(s.find(name))].parent = parent.empty() ? -1 : s.find(parent);
    for (std::size_t j = 0; j < s.joints.size(); ++j) {
      Joint& joint = s.joints[j];
      if (joint.parent < 0) continue;
      const Eigen::Matrix4d local = (world[static_cast<std::size_t>(joint.parent)].inverse() * world[j]).matrix();
      joint.rest = decomposed(local, fmt::format("the rest transform of joint \"{}\" relative to \"{}\"", one_line(joint.name),
                                                 one_line(s.joints[static_cast<std::size_t>(joint.parent)].name)));
    }
    out.hierarchy = "names";
  }

  const fs::path& path_;
  const tinygltf::Model& m_;
  std::vector<int> parent_;         ///< per node: its parent node, or −1
  std::vector<int> joint_of_node_;  ///< per node: its joint in the skin, or −1
  std::vector<Eigen::Matrix4d> between_;  ///< per joint: the nodes' transforms folded into its rest transform
  bool animated_ = false;           ///< some clip animates a joint
};

}  // namespace

RiggedModel read_gltf(const std::filesystem::path& path) {
  const tinygltf::Model model = gltf::load(path);
  return Builder(path, model).build();
}

}  // namespace snh
