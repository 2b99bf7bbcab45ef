#include <numbers>

#include "snh/setup/scene/sections.hpp"

namespace snh::scene {
namespace {

/// One key: {"time": t, "axis": [x, y, z], "degrees": a} or {"time": t, "quaternion": [x, y, z, w]}.
std::pair<double, Eigen::Quaterniond> parse_key(const json& j, const std::string& path, const std::string& file) {
  Keys k(j, path, file);
  if (!k.has("time")) k.fail("needs a time");
  const double t = k.non_negative("time", 0.0);
  const json* q = k.get("quaternion");
  const bool angle = k.has("axis") || k.has("degrees");
  if ((q != nullptr) == angle) k.fail("give axis and degrees, or a quaternion [x, y, z, w]");
  Eigen::Quaterniond r;
  if (q) {
    if (!q->is_array() || q->size() != 4) k.fail("expected 4 numbers [x, y, z, w], got " + q->dump(), "quaternion");
    double c[4];
    for (int i = 0; i < 4; ++i) {
      if (!(*q)[i].is_number() || !std::isfinite((*q)[i].get<double>()) || !(std::abs((*q)[i].get<double>()) <= max_magnitude))
        k.fail(fmt::format("expected 4 finite numbers at most {:g} in magnitude, got {}", max_magnitude, q->dump()), "quaternion");
      c[i] = (*q)[i].get<double>();
    }
    r = Eigen::Quaterniond(c[3], c[0], c[1], c[2]);
    if (!(r.norm() > 1e-12)) k.fail("a zero quaternion is no rotation", "quaternion");
    r.normalize();
  } else {
    const auto axis = k.vec3("axis");
    if (!axis || axis->norm() == 0.0) k.fail("needs a non-zero axis: [ax, ay, az]");
    if (!k.has("degrees")) k.fail("needs degrees");
    r = Eigen::Quaterniond(Eigen::AngleAxisd(k.number("degrees", 0.0) * std::numbers::pi / 180.0, axis->normalized()));
  }
  k.finish();
  return {t, r};
}

}  // namespace

std::optional<FleshSpec> parse_flesh(Keys& top, const std::filesystem::path& source) {
  const json* flesh = top.get("flesh");
  if (!flesh) return std::nullopt;
  if (top.has("mesh")) top.fail("give a mesh or a flesh model, not both", "mesh");
  Keys k(*flesh, "flesh", top.file());
  FleshSpec s;
  const json* model = k.get("model");
  if (!model || !model->is_string() || model->get<std::string>().empty()) k.fail("needs model: a rigged model file (.glb, .gltf, .fbx, .dae, .x, …)");
  const std::filesystem::path f = model->get<std::string>();
  s.model = f.is_absolute() ? f : source.parent_path() / f;
  s.volume = k.choice("volume", "lattice", {"lattice", "tets"}) == "tets" ? FleshVolume::tets : FleshVolume::lattice;
  s.resolution = static_cast<int>(k.integer("resolution", s.resolution, 1, 1000));
  if (k.has("cell_size")) s.cell_size = k.positive("cell_size", 1.0);
  if (k.has("resolution") && k.has("cell_size")) k.fail("give a resolution or a cell_size, not both", "cell_size");
  if (const json* a = k.get("animation")) {
    if (a->is_string() && !a->get<std::string>().empty()) s.animation = a->get<std::string>();
    else if (a->is_number_integer() && a->get<long long>() >= 0) s.animation = std::to_string(a->get<long long>());
    else k.fail("expected a clip name or index, got " + a->dump(), "animation");
  }
  if (const json* keys = k.get("keyframes")) {
    if (!keys->is_array() || keys->empty()) k.fail("expected an array of keyframed joints", "keyframes");
    for (std::size_t i = 0; i < keys->size(); ++i) {
      const std::string path = fmt::format("flesh.keyframes[{}]", i);
      Keys e((*keys)[i], path, top.file());
      KeyframeSpec spec;
      const json* joints = e.get("joints");
      if (!joints || !joints->is_array() || joints->empty()) e.fail("needs joints: an array of joint names");
      for (const json& name : *joints) {
        if (!name.is_string() || name.get<std::string>().empty()) e.fail("expected joint names, got " + name.dump(), "joints");
        spec.joints.push_back(name.get<std::string>());
      }
      const json* ks = e.get("keys");
      if (!ks || !ks->is_array() || ks->empty()) e.fail("needs keys: an array of {time, axis, degrees}");
      for (std::size_t n = 0; n < ks->size(); ++n) {
        const auto [t, r] = parse_key((*ks)[n], fmt::format("{}.keys[{}]", path, n), top.file());
        if (!spec.times.empty() && !(t > spec.times.back()))
          e.fail(fmt::format("key times must increase: {:g} after {:g}", t, spec.times.back()), fmt::format("keys[{}]", n));
        spec.times.push_back(t);
        spec.rotations.push_back(r);
      }
      e.finish();
      s.keyframes.push_back(std::move(spec));
    }
  }
  if (!s.animation.empty() && !s.keyframes.empty()) k.fail("give animation or keyframes, not both");
  if (const json* bones = k.get("bones")) {
    if (!bones->is_array()) k.fail("expected an array of {joint, radius}", "bones");
    for (std::size_t i = 0; i < bones->size(); ++i) {
      Keys b((*bones)[i], fmt::format("flesh.bones[{}]", i), top.file());
      const json* joint = b.get("joint");
      if (!joint || !joint->is_string() || joint->get<std::string>().empty()) b.fail("needs joint: a joint name");
      if (!b.has("radius")) b.fail("needs radius");
      s.radii.push_back({joint->get<std::string>(), b.positive("radius", 0.0)});
      b.finish();
    }
  }
  s.radius_scale = k.positive("radius_scale", s.radius_scale);
  const std::string joints = k.choice("joint_cells", to_string(s.joint_cells), {"soft", "free", "hard"});
  s.joint_cells = joints == "soft" ? JointCells::soft : joints == "free" ? JointCells::free : JointCells::hard;
  s.split_cells = k.boolean("split_cells", s.split_cells);
  s.join_meshes = k.boolean("join_meshes", s.join_meshes);
  s.fps = k.positive("fps", s.fps);
  if (s.fps > 1e6) k.fail(fmt::format("must be at most 1e6 frames per second, got {:g}", s.fps), "fps");
  if (const json* soft = k.get("soft_binding")) {
    Keys b(*soft, "flesh.soft_binding", top.file());
    if (b.has("shell")) s.soft_shell = b.positive("shell", 0.0);
    s.soft_stiffness = b.positive("stiffness", s.soft_stiffness);
    b.finish();
  }
  k.finish();
  return s;
}

}  // namespace snh::scene
