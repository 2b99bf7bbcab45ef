#include "snh/io/surface_read.hpp"
#include "snh/setup/scene/sections.hpp"

namespace snh::scene {

ContactSpec parse_contact(Keys& top, const std::filesystem::path& source, double end_time) {
  ContactSpec s;
  if (const json* c = top.get("contact")) {
    Keys k(*c, "contact", top.file());
    s.enabled = true;
    s.self = k.boolean("self", s.self);
    // A flesh scene may leave dhat and stiffness to its defaults (flesh_contact_dhat and _stiffness, resolved
    // by the build once the flesh is built): unset here.
    const bool flesh = top.has("flesh");
    if (k.has("bones") && !flesh) k.fail("only a flesh scene has bones", "bones");
    s.bones = k.boolean("bones", s.bones);
    if (!k.has("dhat") && !flesh) k.fail("required: the distance below which surfaces repel (> 0)", "dhat");
    if (k.has("dhat")) s.dhat = k.positive("dhat", 0.0);
    // kappa left out or "auto": unset, chosen by the build (volume_contact: IPC's rule when dynamic,
    // the elastic rule quasi-statically; a flesh's own rule).
    if (const json* st = k.get("stiffness"); st && st->is_string()) {
      if (st->get<std::string>() != "auto") k.fail("expected a number > 0 or \"auto\", got " + st->dump(), "stiffness");
    } else if (st) {
      s.stiffness = k.positive("stiffness", 0.0);
    }
    s.friction = k.non_negative("friction", 0.0);
    if (k.get("friction_velocity") && !(s.friction > 0.0)) k.fail("has no effect without friction > 0", "friction_velocity");
    if (k.has("friction_velocity")) s.friction_velocity = k.positive("friction_velocity", 0.0);
    k.finish();
  }
  if (const json* list = top.get("colliders")) {
    if (!list->is_array()) top.fail("expected an array of colliders, got " + list->dump(), "colliders");
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string path = fmt::format("colliders[{}]", i);
      Keys k((*list)[i], path, top.file());
      if (!k.has("type")) k.fail("required: the collider's type (plane, sphere, capsule, box or mesh)", "type");
      const std::string type = k.choice("type", "plane", {"plane", "sphere", "capsule", "box", "mesh"});
      ColliderSpec c;
      c.index = static_cast<int>(i);
      if (const json* motions = k.get("motion")) {
        if (!motions->is_array()) k.fail("expected an array of motions", "motion");
        for (std::size_t m = 0; m < motions->size(); ++m) {
          const std::string at = fmt::format("{}.motion[{}]", path, m);
          c.motions.push_back(parse_motion((*motions)[m], at, top.file(), end_time));
          // A shape stays a shape under rotations, translations and uniform scales only.
          if (const auto* scale = std::get_if<Scale>(&c.motions.back()); scale && type != "mesh" &&
              !(scale->factors[0] == scale->factors[1] && scale->factors[1] == scale->factors[2]))
            Keys((*motions)[m], at, top.file()).fail("a " + type + " collider scales only with three equal factors (a mesh collider takes any)", "factors");
        }
      }
      const auto required = [&](const char* key, const char* what) {
        const auto v = k.vec3(key);
        if (!v) k.fail(std::string("required: ") + what + ", 3 numbers", key);
        return *v;
      };
      const auto radius = [&](const std::string& shape) {
        if (!k.has("radius")) k.fail("required: the " + shape + "'s radius (> 0)", "radius");
        return k.positive("radius", 0.0);
      };
      if (type == "plane") {
        c.type = ColliderSpec::Type::plane;
        c.a = required("point", "a point of the plane");
        c.b = required("normal", "the plane's normal (the side kept free)");
        if (!(c.b.norm() > 0.0)) k.fail("must not be zero", "normal");
        c.b.normalize();
      } else if (type == "sphere") {
        c.type = ColliderSpec::Type::sphere;
        c.a = required("center", "the sphere's centre");
        c.radius = radius("sphere");
      } else if (type == "capsule") {
        c.type = ColliderSpec::Type::capsule;
        c.a = required("a", "one end of the capsule's segment");
        c.b = required("b", "the other end of the capsule's segment");
        c.radius = radius("capsule");
      } else if (type == "box") {
        c.type = ColliderSpec::Type::box;
        c.a = required("center", "the box's centre");
        const Eigen::Vector3d size = required("size", "the box's edge lengths along x, y and z");
        if (!(size.array() > 0.0).all()) k.fail(fmt::format("expected 3 edge lengths > 0, got [{:g}, {:g}, {:g}]", size[0], size[1], size[2]), "size");
        c.b = 0.5 * size;
      } else {
        c.type = ColliderSpec::Type::mesh;
        const json* file = k.get("file");
        if (!file) k.fail("required: the collider's surface file (.obj, .off, .ply or .stl)", "file");
        if (!file->is_string() || file->get<std::string>().empty()) k.fail("expected a file name, got " + file->dump(), "file");
        const std::filesystem::path f = file->get<std::string>();
        c.file = f.is_absolute() ? f : source.parent_path() / f;
        if (!is_surface_file(c.file)) k.fail("expected a .obj, .off, .ply or .stl file, got " + file->dump(), "file");
      }
      k.finish();
      if (c.type == ColliderSpec::Type::plane && c.motions.empty()) s.planes.push_back({c.a, c.b, c.index});
      else s.colliders.push_back(std::move(c));
    }
    if (!s.enabled && !list->empty())
      top.fail("colliders need a \"contact\" section (its dhat and stiffness)", "colliders");
  }
  if (s.friction > 0.0 && !s.self && s.planes.empty() &&
      std::none_of(s.colliders.begin(), s.colliders.end(), [](const ColliderSpec& c) { return c.type != ColliderSpec::Type::mesh; }))
    Keys(*top.get("contact"), "contact", top.file())
        .fail("acts in self-contact and against plane, sphere, capsule and box colliders, and this scene has none of them (mesh "
              "colliders are frictionless)",
              "friction");
  return s;
}

void read_collider_mesh(ColliderSpec& c, const std::string& file) {
  const auto fail = [&](const std::string& what) {
    throw SceneError(fmt::format("{}: colliders[{}].file: {}", file, c.index, what));
  };
  SurfaceMesh surface;
  try {
    surface = read_surface(c.file);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  if (surface.triangles.cols() == 0) fail(fmt::format("{} has no triangles", c.file.string()));
  if (!(surface.vertices.array().abs() <= max_magnitude).all())
    fail(fmt::format("{} has a coordinate beyond the {:g} a scene allows", c.file.string(), max_magnitude));
  for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t) {
    const auto& T = surface.triangles.col(t);
    if (T[0] == T[1] || T[1] == T[2] || T[2] == T[0]) fail(fmt::format("{}: triangle {} repeats a vertex", c.file.string(), t));
  }
  c.vertices = std::move(surface.vertices);
  c.triangles = std::move(surface.triangles);
}

}  // namespace snh::scene
