#include <set>

#include "snh/setup/scene/sections.hpp"

namespace snh::scene {
namespace {

/// [x, y, z] (a fixed point), "JOINT" (its rest position) or {"joint": JOINT, "point": [x, y, z]}.
MusclePoint parse_point(Keys& k, const std::string& key, bool flesh) {
  const json* j = k.get(key);
  if (!j) k.fail("needs " + key + ": [x, y, z], a joint name or {\"joint\": NAME, \"point\": [x, y, z]}");
  MusclePoint p;
  if (j->is_array()) {
    p.point = k.vec3(key);
    return p;
  }
  const auto need_flesh = [&] {
    if (!flesh) k.fail("a joint names a point only in a flesh scene (give [x, y, z])", key);
  };
  if (j->is_string()) {
    if (j->get<std::string>().empty()) k.fail("expected a joint name, got \"\"", key);
    need_flesh();
    p.joint = j->get<std::string>();
    return p;
  }
  Keys o(*j, k.path(key), k.file());
  const json* joint = o.get("joint");
  if (!joint || !joint->is_string() || joint->get<std::string>().empty()) o.fail("needs joint: a joint name");
  need_flesh();
  p.joint = joint->get<std::string>();
  p.point = o.vec3("point");
  o.finish();
  return p;
}

RegionSpec parse_region(Keys& k, const std::filesystem::path& source, bool flesh) {
  const json* j = k.get("region");
  if (!j) k.fail("needs region: {\"min\": [x, y, z], \"max\": [x, y, z]}, {\"mesh\": FILE}, {\"model_mesh\": NAME} or {\"tags\": [N, ...]}");
  Keys r(*j, k.path("region"), k.file());
  RegionSpec s;
  const bool box = r.has("min") || r.has("max"), mesh = r.has("mesh"), model = r.has("model_mesh"), tags = r.has("tags");
  if (int(box) + int(mesh) + int(model) + int(tags) != 1) r.fail("give min and max, a mesh file, a model_mesh or tags: one of them");
  if (tags) {
    const json* t = r.get("tags");
    if (!t->is_array() || t->empty()) r.fail("expected an array of the mesh file's cell tags (integers), got " + t->dump(), "tags");
    for (const json& v : *t) {
      if (!v.is_number_integer()) r.fail("expected integer tags, got " + v.dump(), "tags");
      s.tags.push_back(v.get<long long>());
    }
    if (flesh) r.fail("a flesh volume has no cell tags (they come from a mesh file)", "tags");
    s.kind = RegionSpec::Kind::tags;
  } else if (box) {
    const auto lo = r.vec3("min"), hi = r.vec3("max");
    if (!lo || !hi) r.fail("min and max go together");
    if (!((lo->array() < hi->array()).all())) r.fail("min must be below max on every axis");
    s.box = Eigen::AlignedBox3d(*lo, *hi);
  } else {
    const std::string key = mesh ? "mesh" : "model_mesh";
    const json* v = r.get(key);
    if (!v->is_string() || v->get<std::string>().empty()) r.fail(mesh ? "expected a surface file name" : "expected a mesh name", key);
    if (mesh) {
      s.kind = RegionSpec::Kind::mesh;
      const std::filesystem::path f = v->get<std::string>();
      s.file = f.is_absolute() ? f : source.parent_path() / f;
    } else {
      if (!flesh) r.fail("a model's mesh names a region only in a flesh scene", key);
      s.kind = RegionSpec::Kind::model_mesh;
      s.model_mesh = v->get<std::string>();
    }
  }
  r.finish();
  return s;
}

/// "activation": [{"time": t, "value": a}, ...] or {"line_of_action": {"from", "to", "gain", "max"}}.
void parse_activation(Keys& k, MuscleSpec& m, bool flesh) {
  const json* a = k.get("activation");
  if (!a) return;
  if (a->is_array()) {
    if (a->empty()) k.fail("expected keys [{\"time\": t, \"value\": a}, ...] or {\"line_of_action\": ...}", "activation");
    for (std::size_t i = 0; i < a->size(); ++i) {
      Keys e((*a)[i], k.path(fmt::format("activation[{}]", i)), k.file());
      if (!e.has("time") || !e.has("value")) e.fail("needs time and value");
      ActivationKey key{e.non_negative("time", 0.0), e.number("value", 0.0)};
      if (!(key.value >= 0.0 && key.value <= 1.0)) e.fail(fmt::format("must be from 0 to 1, got {:g}", key.value), "value");
      if (!m.keys.empty() && !(key.time > m.keys.back().time))
        e.fail(fmt::format("key times must increase: {:g} after {:g}", key.time, m.keys.back().time), "time");
      e.finish();
      m.keys.push_back(key);
    }
    return;
  }
  Keys o(*a, k.path("activation"), k.file());
  const json* line = o.get("line_of_action");
  if (!line) o.fail("expected keys [{\"time\": t, \"value\": a}, ...] or {\"line_of_action\": {\"from\", \"to\", \"gain\"}}");
  if (!flesh) o.fail("a line of action needs a flesh scene's joints", "line_of_action");
  Keys l(*line, o.path("line_of_action"), k.file());
  LineOfAction s;
  s.from = parse_point(l, "from", flesh);
  s.to = parse_point(l, "to", flesh);
  if (s.from.joint.empty() || s.to.joint.empty()) l.fail("from and to must each follow a joint (a joint name or {\"joint\", \"point\"})");
  s.gain = l.positive("gain", s.gain);
  s.max = l.positive("max", s.max);
  if (s.max > 1.0) l.fail(fmt::format("must be at most 1, got {:g}", s.max), "max");
  l.finish();
  o.finish();
  m.line = s;
}

MuscleSpec parse_entry(const json& j, const std::string& path, const std::string& file, const std::filesystem::path& source,
                       bool flesh, bool muscle) {
  Keys k(j, path, file);
  MuscleSpec m;
  m.muscle = muscle;
  const json* name = k.get("name");
  if (!name || !name->is_string() || name->get<std::string>().empty()) k.fail("needs name: a name for messages and output");
  m.name = name->get<std::string>();
  for (const unsigned char c : m.name)
    if (c < 0x20 || c == 0x7f) k.fail("a name may not hold control characters", "name");
  m.region = parse_region(k, source, flesh);
  if (const json* mat = k.get("material")) m.material = parse_material_object(*mat, k.path("material"), file, MaterialChoice{});
  if (!muscle) {
    if (const json* bone = k.get("bone")) {
      if (!bone->is_string() || bone->get<std::string>().empty()) k.fail("expected a joint name, got " + bone->dump(), "bone");
      if (!flesh) k.fail("a bone region needs a flesh scene's joints", "bone");
      m.bone = bone->get<std::string>();
    }
    k.finish();
    return m;
  }
  const json* fibre = k.get("fibre");
  if (!fibre) k.fail("needs fibre: [x, y, z], {\"origin\": POINT, \"insertion\": POINT} or {\"file\": FILE}");
  if (fibre->is_array()) {
    const auto d = k.vec3("fibre");
    if (!(d->norm() > 0.0)) k.fail("a fibre direction must not be zero", "fibre");
    m.direction = d->normalized();
  } else {
    Keys f(*fibre, k.path("fibre"), file);
    if (f.has("file")) {
      const json* name = f.get("file");
      if (!name->is_string() || name->get<std::string>().empty()) f.fail("expected a file name, got " + name->dump(), "file");
      if (f.has("origin") || f.has("insertion") || f.has("reach")) f.fail("give a file, or an origin and an insertion: not both");
      const std::filesystem::path p = name->get<std::string>();
      m.fibre_file = p.is_absolute() ? p : source.parent_path() / p;
      m.field = MuscleSpec::Field::file;
    } else {
      m.field = MuscleSpec::Field::harmonic;
      m.origin = parse_point(f, "origin", flesh);
      m.insertion = parse_point(f, "insertion", flesh);
      if (f.has("reach")) m.reach = f.positive("reach", 1.0);
    }
    f.finish();
  }
  m.fibre_model = k.choice("fibre_model", "signed_arap", {"signed_arap", "quadratic"}) == "quadratic" ? FibreModel::quadratic
                                                                                                       : FibreModel::signed_arap;
  if (k.has("fibre_stiffness")) m.fibre_stiffness = k.non_negative("fibre_stiffness", 0.0);
  m.contraction = k.non_negative("contraction", m.contraction);
  if (!(m.contraction < 1.0)) k.fail(fmt::format("must be below 1 (the fibres' rest length is 1 - contraction at full activation), got {:g}", m.contraction),
                                     "contraction");
  parse_activation(k, m, flesh);
  k.finish();
  return m;
}

}  // namespace

std::vector<MuscleSpec> parse_muscles(Keys& top, const std::filesystem::path& source, bool flesh) {
  std::vector<MuscleSpec> out;
  std::set<std::string> names;
  for (const char* list : {"tissues", "muscles"}) {
    const json* j = top.get(list);
    if (!j) continue;
    if (!j->is_array()) top.fail("expected an array of regions", list);
    for (std::size_t i = 0; i < j->size(); ++i) {
      const std::string path = fmt::format("{}[{}]", list, i);
      MuscleSpec m = parse_entry((*j)[i], path, top.file(), source, flesh, std::string_view(list) == "muscles");
      if (!names.insert(m.name).second) top.fail(fmt::format("the name \"{}\" is given twice", m.name), path + ".name");
      out.push_back(std::move(m));
    }
  }
  return out;
}

}  // namespace snh::scene
