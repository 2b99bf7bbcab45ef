#include "snh/sim/scene/sections.hpp"

namespace snh::scene {

ContactSpec parse_contact(Keys& top, Integrator integrator) {
  ContactSpec s;
  if (const json* c = top.get("contact")) {
    Keys k(*c, "contact", top.file());
    s.enabled = true;
    s.self = k.boolean("self", s.self);
    // A flesh scene may leave dhat and stiffness to its defaults (flesh_contact_dhat and _stiffness, set
    // once the flesh is built): 0 here.
    const bool flesh = top.has("flesh");
    if (!k.has("dhat") && !flesh) k.fail("required: the distance below which surfaces repel (> 0)", "dhat");
    s.dhat = k.has("dhat") ? k.positive("dhat", 0.0) : 0.0;
    if (!k.has("stiffness") && !flesh) k.fail("required: the barrier's stiffness kappa (> 0, or \"auto\")", "stiffness");
    if (const json* st = k.get("stiffness"); !st) {
      s.stiffness = 0.0;
    } else if (st->is_string()) {
      if (st->get<std::string>() != "auto") k.fail("expected a number > 0 or \"auto\", got " + st->dump(), "stiffness");
      if (integrator != Integrator::backward_euler && !flesh)
        k.fail("\"auto\" needs backward_euler (its masses and time step set the scale): give a number", "stiffness");
      s.stiffness = 0.0;  // auto: chosen on the mesh (ipc_barrier_stiffness)
    } else {
      s.stiffness = k.positive("stiffness", 0.0);
    }
    k.finish();
  }
  if (const json* list = top.get("colliders")) {
    if (!list->is_array()) top.fail("expected an array of colliders, got " + list->dump(), "colliders");
    for (std::size_t i = 0; i < list->size(); ++i) {
      Keys k((*list)[i], fmt::format("colliders[{}]", i), top.file());
      if (!k.has("type")) k.fail("required: the collider's type (plane)", "type");
      (void)k.choice("type", "plane", {"plane"});
      PlaneColliderSpec plane;
      const auto point = k.vec3("point"), normal = k.vec3("normal");
      if (!point) k.fail("required: a point of the plane, 3 numbers", "point");
      if (!normal) k.fail("required: the plane's normal (the side kept free), 3 numbers", "normal");
      if (!(normal->norm() > 0.0)) k.fail("must not be zero", "normal");
      plane.point = *point;
      plane.normal = normal->normalized();
      k.finish();
      s.planes.push_back(plane);
    }
    if (!s.enabled && !s.planes.empty())
      top.fail("colliders need a \"contact\" section (its dhat and stiffness)", "colliders");
  }
  return s;
}

}  // namespace snh::scene
