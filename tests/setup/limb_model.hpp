#pragma once
// A procedural rigged limb for the flesh tests: a closed cylinder along x (from 0 to 2, radius r) with three
// joints in a chain, shoulder (x = 0) → elbow (x = 1) → tip (x = 2), skinned with weights that blend from
// the shoulder to the elbow over [1 − blend, 1 + blend], and a clip that bends the elbow by `degrees` about z
// over one second. Written as a .gltf with its buffer embedded (a base64 data: URI).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "snh/io/base64.hpp"

namespace snh::test {

struct LimbOptions {
  double radius = 0.3;
  int around = 16, along = 24;  ///< vertices per ring, rings
  double blend = 0.2;           ///< half-width of the skinning blend at the elbow
  double degrees = 90.0;
  bool caps = true;             ///< false: the cylinder's ends stay open (not a solid)
  /// An armature node above the shoulder, scaling by this and turning by armature_degrees about x, that the
  /// skin's inverse bind matrices leave out (as FBX conversions do): the rest pose puts the skin elsewhere.
  double armature_scale = 1.0, armature_degrees = 0.0;
  /// The elbow's rest rotation about z (the skin is bound straight): a rest pose that is not the bind pose.
  double rest_elbow_degrees = 0.0;
  double duration = 1.0;        ///< the clip's length in seconds
  bool inside_out = false;      ///< triangles wound clockwise seen from outside
  /// Two mesh nodes sharing the skin and the vertices, each with half of the triangles (a character in parts).
  bool two_meshes = false;
  bool still_clip_first = false;  ///< a one-key "bind" clip before "bend" (as FBX conversions write)
  /// > 0: a second, still limb beside the first (the same cylinder moved by 2 radius + gap along z), skinned to
  /// a chain of its own (a second root joint "still" → "still_tip"), so the gap between them is that wide.
  double beside_gap = 0.0;
  /// > 0: the still limb sunk this far into the first (its axis 2 radius − overlap away), in a mesh of its own.
  double beside_overlap = 0.0;
  /// The limb in two meshes that meet at the ring nearest the elbow (each with its own copy of that ring's
  /// vertices): the upper one skinned wholly to the shoulder, the lower one to the elbow.
  bool split_at_elbow = false;
  /// > 0: a box of side 0.2 without a skin, a child of the tip's node this far beyond it (a prop held at the tip).
  double rigid_cap = 0.0;
};

inline void write_limb_gltf(const std::filesystem::path& path, const LimbOptions& o = {}) {
  std::vector<float> pos, weights;
  std::vector<std::uint16_t> joints;
  std::vector<std::uint32_t> idx;
  const bool beside = o.beside_gap > 0.0 || o.beside_overlap > 0.0;
  const double seam_x = 2.0 * ((o.along - 1) / 2) / (o.along - 1);  // the ring nearest the elbow (split_at_elbow)
  bool lower = false;   // the vertices made now are the lower mesh's copy of the seam (split_at_elbow)
  bool still = false;   // the vertices made now belong to the still limb
  double offset = 0.0;  // its z offset
  auto vertex = [&](double x, double y, double z) {
    pos.insert(pos.end(), {float(x), float(y), float(z + offset)});
    double s = std::clamp((x - (1.0 - o.blend)) / (2.0 * o.blend), 0.0, 1.0);  // elbow's share
    if (o.split_at_elbow) s = x > seam_x + 1e-9 || lower ? 1.0 : 0.0;
    joints.insert(joints.end(), {std::uint16_t(still ? 3 : 0), 1, 0, 0});
    weights.insert(weights.end(), {float(still ? 1.0 : 1.0 - s), float(still ? 0.0 : s), 0.0f, 0.0f});
    return static_cast<std::uint32_t>(pos.size() / 3 - 1);
  };
  const auto cylinder = [&] {
    const auto base = static_cast<std::uint32_t>(pos.size() / 3);
    for (int i = 0; i < o.along; ++i) {
      const double x = 2.0 * i / (o.along - 1);
      for (int k = 0; k < o.around; ++k) {
        const double a = 2.0 * std::numbers::pi * k / o.around;
        vertex(x, o.radius * std::cos(a), o.radius * std::sin(a));
      }
    }
    const std::uint32_t c0 = vertex(0, 0, 0), c1 = vertex(2, 0, 0);
    auto ring = [&](int i, int k) { return base + static_cast<std::uint32_t>(i * o.around + (k % o.around)); };
    for (int i = 0; i + 1 < o.along; ++i)
      for (int k = 0; k < o.around; ++k)  // outward: counter-clockwise seen from outside
        idx.insert(idx.end(), {ring(i, k), ring(i, k + 1), ring(i + 1, k + 1), ring(i, k), ring(i + 1, k + 1), ring(i + 1, k)});
    for (int k = 0; k < o.around && o.caps; ++k) {
      idx.insert(idx.end(), {c0, ring(0, k + 1), ring(0, k)});
      idx.insert(idx.end(), {c1, ring(o.along - 1, k), ring(o.along - 1, k + 1)});
    }
  };
  cylinder();
  std::size_t first_half = idx.size();  // the first mesh's triangles (two_meshes, beside_overlap, split_at_elbow)
  if (beside) {
    first_half = idx.size();
    still = true;
    offset = 2.0 * o.radius + o.beside_gap - o.beside_overlap;
    cylinder();
  }
  if (o.split_at_elbow) {
    // Triangles between rings below the seam ring, and the shoulder's cap, stay in the first mesh; the others
    // go to the second, on a copy of the seam ring's vertices.
    const int seam = (o.along - 1) / 2;
    lower = true;
    std::vector<std::uint32_t> copy(static_cast<std::size_t>(o.around));
    for (int k = 0; k < o.around; ++k) {
      const double a = 2.0 * std::numbers::pi * k / o.around;
      copy[static_cast<std::size_t>(k)] = vertex(seam_x, o.radius * std::cos(a), o.radius * std::sin(a));
    }
    std::vector<std::uint32_t> upper, rest;
    const auto ring_of = [&](std::uint32_t v) { return v < static_cast<std::uint32_t>(o.along * o.around) ? int(v) / o.around : -1; };
    for (std::size_t t = 0; t < idx.size(); t += 3) {
      int top = -1;  // the highest ring a corner is on (caps' centres: none)
      for (int c = 0; c < 3; ++c) top = std::max(top, ring_of(idx[t + c]));
      const bool tip_cap = idx[t] == static_cast<std::uint32_t>(o.along * o.around + 1);
      std::vector<std::uint32_t>& to = top <= seam && !tip_cap ? upper : rest;
      for (int c = 0; c < 3; ++c) {
        std::uint32_t v = idx[t + c];
        if (&to == &rest && ring_of(v) == seam) v = copy[v % static_cast<std::uint32_t>(o.around)];
        to.push_back(v);
      }
    }
    idx = upper;
    first_half = idx.size();
    idx.insert(idx.end(), rest.begin(), rest.end());
  }
  if (o.inside_out)
    for (std::size_t t = 0; t + 2 < idx.size(); t += 3) std::swap(idx[t + 1], idx[t + 2]);
  // Inverse bind matrices (column-major): translations by −x of each joint.
  std::vector<float> ibm;
  const double z_still = 2.0 * o.radius + o.beside_gap - o.beside_overlap;
  for (const auto& [x, z] : std::initializer_list<std::pair<double, double>>{{0.0, 0.0}, {1.0, 0.0}, {2.0, 0.0}, {0.0, z_still}, {2.0, z_still}}) {
    const float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float(-x), 0, float(0.0 - z), 1};
    ibm.insert(ibm.end(), m, m + 16);
  }
  const double half = 0.5 * o.degrees * std::numbers::pi / 180.0;
  const std::vector<float> times{0.0f, float(o.duration)},
      rotations{0, 0, 0, 1, 0, 0, float(std::sin(half)), float(std::cos(half))};

  std::string bin;
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array();
  auto add = [&](const void* data, std::size_t bytes, int component, std::size_t count, const char* type, int target) {
    while (bin.size() % 4) bin.push_back('\0');
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target) view["target"] = target;
    bin.append(static_cast<const char*>(data), bytes);
    views.push_back(view);
    accessors.push_back({{"bufferView", views.size() - 1}, {"componentType", component}, {"count", count}, {"type", type}});
    return static_cast<int>(accessors.size() - 1);
  };
  const int a_pos = add(pos.data(), pos.size() * 4, 5126, pos.size() / 3, "VEC3", 34962);
  accessors[a_pos]["min"] = {0.0, -o.radius, -o.radius};
  accessors[a_pos]["max"] = {2.0, o.radius, o.radius + (beside ? z_still : 0.0)};
  const int a_joints = add(joints.data(), joints.size() * 2, 5123, joints.size() / 4, "VEC4", 34962);
  const int a_weights = add(weights.data(), weights.size() * 4, 5126, weights.size() / 4, "VEC4", 34962);
  const bool second_mesh = o.two_meshes || o.beside_overlap > 0.0 || o.split_at_elbow;
  if (o.two_meshes) first_half = idx.size() / 6 * 3;
  if (!second_mesh) first_half = idx.size();
  const int a_idx = add(idx.data(), first_half * 4, 5125, first_half, "SCALAR", 34963);
  const int a_idx2 = second_mesh ? add(idx.data() + first_half, (idx.size() - first_half) * 4, 5125, idx.size() - first_half, "SCALAR", 34963) : -1;
  const int joint_count = beside ? 5 : 3;
  const int a_ibm = add(ibm.data(), static_cast<std::size_t>(joint_count) * 64, 5126, static_cast<std::size_t>(joint_count), "MAT4", 0);
  const int a_t = add(times.data(), times.size() * 4, 5126, 2, "SCALAR", 0);
  accessors[a_t]["min"] = {0.0};
  accessors[a_t]["max"] = {float(o.duration)};
  const int a_r = add(rotations.data(), rotations.size() * 4, 5126, 2, "VEC4", 0);

  nlohmann::json g;
  g["asset"] = {{"version", "2.0"}};
  g["scene"] = 0;
  const bool armature = o.armature_scale != 1.0 || o.armature_degrees != 0.0;
  g["scenes"] = nlohmann::json::array({nlohmann::json{{"nodes", {0, armature ? 4 : 1}}}});
  if (second_mesh) g["scenes"][0]["nodes"].push_back(armature ? 5 : 4);
  g["nodes"] = nlohmann::json::array({nlohmann::json{{"name", "limb"}, {"mesh", 0}, {"skin", 0}},
                                      nlohmann::json{{"name", "shoulder"}, {"children", {2}}},
                                      nlohmann::json{{"name", "elbow"}, {"translation", {1.0, 0.0, 0.0}}, {"children", {3}}},
                                      nlohmann::json{{"name", "tip"}, {"translation", {1.0, 0.0, 0.0}}}});
  if (o.rest_elbow_degrees != 0.0) {
    const double r = 0.5 * o.rest_elbow_degrees * std::numbers::pi / 180.0;
    g["nodes"][2]["rotation"] = {0.0, 0.0, std::sin(r), std::cos(r)};
  }
  if (armature) {
    const double a = 0.5 * o.armature_degrees * std::numbers::pi / 180.0;
    g["nodes"].push_back({{"name", "armature"}, {"children", {1}}, {"rotation", {std::sin(a), 0.0, 0.0, std::cos(a)}},
                          {"scale", {o.armature_scale, o.armature_scale, o.armature_scale}}, {"translation", {5.0, -3.0, 2.0}}});
  }
  nlohmann::json primitive = {{"attributes", {{"POSITION", a_pos}, {"JOINTS_0", a_joints}, {"WEIGHTS_0", a_weights}}},
                               {"indices", a_idx}};
  g["meshes"] = nlohmann::json::array({nlohmann::json{{"primitives", nlohmann::json::array({primitive})}}});
  if (second_mesh) {
    primitive["indices"] = a_idx2;
    g["meshes"].push_back({{"primitives", nlohmann::json::array({primitive})}});
    g["nodes"].push_back({{"name", "limb_far"}, {"mesh", 1}, {"skin", 0}});
  }
  g["skins"] = nlohmann::json::array({nlohmann::json{{"joints", {1, 2, 3}}, {"inverseBindMatrices", a_ibm}}});
  if (o.rigid_cap > 0.0) {
    std::vector<float> box;
    for (int c = 0; c < 8; ++c) box.insert(box.end(), {c & 1 ? 0.1f : -0.1f, c & 2 ? 0.1f : -0.1f, c & 4 ? 0.1f : -0.1f});
    const std::vector<std::uint16_t> faces = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                              2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
    const int a_box = add(box.data(), box.size() * 4, 5126, 8, "VEC3", 34962);
    accessors[a_box]["min"] = {-0.1, -0.1, -0.1};
    accessors[a_box]["max"] = {0.1, 0.1, 0.1};
    const int a_faces = add(faces.data(), faces.size() * 2, 5123, faces.size(), "SCALAR", 34963);
    g["meshes"].push_back({{"primitives", nlohmann::json::array({{{"attributes", {{"POSITION", a_box}}}, {"indices", a_faces}}})}});
    const int cap = static_cast<int>(g["nodes"].size());
    g["nodes"].push_back({{"name", "cap"}, {"mesh", g["meshes"].size() - 1}, {"translation", {o.rigid_cap, 0.0, 0.0}}});
    g["nodes"][3]["children"] = {cap};
  }
  if (beside) {
    const int first = static_cast<int>(g["nodes"].size());
    g["nodes"].push_back({{"name", "still"}, {"translation", {0.0, 0.0, z_still}}, {"children", {first + 1}}});
    g["nodes"].push_back({{"name", "still_tip"}, {"translation", {2.0, 0.0, 0.0}}});
    g["scenes"][0]["nodes"].push_back(first);
    g["skins"][0]["joints"] = {1, 2, 3, first, first + 1};
  }
  nlohmann::json channel = {{"sampler", 0}, {"target", {{"node", 2}, {"path", "rotation"}}}};
  nlohmann::json sampler = {{"input", a_t}, {"output", a_r}, {"interpolation", "LINEAR"}};
  g["animations"] = nlohmann::json::array({nlohmann::json{{"name", "bend"},
                                                          {"channels", nlohmann::json::array({channel})},
                                                          {"samplers", nlohmann::json::array({sampler})}}});
  if (o.still_clip_first) {  // one key: the first of "bend"'s times and values
    const int a_t1 = add(times.data(), 4, 5126, 1, "SCALAR", 0);
    accessors[a_t1]["min"] = {0.0};
    accessors[a_t1]["max"] = {0.0};
    const int a_r1 = add(rotations.data(), 16, 5126, 1, "VEC4", 0);
    g["accessors"] = accessors;
    g["bufferViews"] = views;
    nlohmann::json still = g["animations"][0];
    still["name"] = "bind";
    still["samplers"][0] = {{"input", a_t1}, {"output", a_r1}, {"interpolation", "LINEAR"}};
    g["animations"].insert(g["animations"].begin(), still);
  }
  g["bufferViews"] = views;
  g["accessors"] = accessors;
  g["buffers"] = nlohmann::json::array(
      {nlohmann::json{{"byteLength", bin.size()},
                      {"uri", "data:application/octet-stream;base64," + base64_encode(bin.data(), bin.size())}}});
  std::ofstream(path) << g.dump();
}

}  // namespace snh::test
