#include <limits>

#include "snh/setup/scene/sections.hpp"

namespace snh::scene {
namespace {

InitialOp parse_op(const json& j, const std::string& path, const std::string& file) {
  Keys k(j, path, file);
  const std::string type = k.choice("type", "", {"scale", "reflect", "collapse", "perturb", "move", "velocity"});
  if (type.empty()) k.fail("needs a type (scale, reflect, collapse, perturb, move or velocity)");
  InitialOp op;
  if (type == "scale") {
    ScaleOp s;
    s.center = k.vec3("center");
    const auto f = k.vec3("factors");
    if (!f) k.fail("scale needs factors: [sx, sy, sz]");
    s.factors = *f;
    op = s;
  } else if (type == "reflect") {
    ReflectOp r;
    r.center = k.vec3("center");
    r.axis = k.axis("axis", "x");
    op = r;
  } else if (type == "collapse") {
    CollapseOp c;
    c.center = k.vec3("center");
    const std::string to = k.choice("to", "point", {"plane", "line", "point"});
    c.to = to == "plane" ? CollapseOp::To::plane : to == "line" ? CollapseOp::To::line : CollapseOp::To::point;
    c.axis = k.axis("axis", "y");
    op = c;
  } else if (type == "perturb") {
    PerturbOp p;
    p.amplitude = k.non_negative("amplitude", p.amplitude);
    p.seed = static_cast<std::uint64_t>(k.integer("seed", 1, 0, std::numeric_limits<long long>::max()));
    op = p;
  } else if (type == "velocity") {
    VelocityOp v;
    if (k.has("region") || k.has("indices")) v.select = parse_selection(k);
    const auto value = k.vec3("value");
    if (!value) k.fail("velocity needs value: [vx, vy, vz]");
    v.value = *value;
    op = v;
  } else {
    MoveOp m;
    m.select = parse_selection(k);
    const auto by = k.vec3("by");
    if (!by) k.fail("move needs by: [dx, dy, dz]");
    m.by = *by;
    op = m;
  }
  k.finish();
  return op;
}

}  // namespace

std::vector<InitialOp> parse_initial(Keys& top) {
  std::vector<InitialOp> out;
  const json* initial = top.get("initial");
  if (!initial) return out;
  if (!initial->is_array()) top.fail("expected an array of operations", "initial");
  for (std::size_t i = 0; i < initial->size(); ++i) out.push_back(parse_op((*initial)[i], fmt::format("initial[{}]", i), top.file()));
  return out;
}

}  // namespace snh::scene
