#include "snh/material/registry.hpp"
#include "snh/setup/scene/sections.hpp"

namespace snh::scene {

MaterialChoice parse_material_object(const json& j, const std::string& path, const std::string& file, const MaterialChoice& defaults) {
  MaterialChoice s = defaults;
  Keys m(j, path, file);
  if (const json* name = m.get("name")) {
    if (!name->is_string()) m.fail("expected a material name, got " + name->dump(), "name");
    s.name = name->get<std::string>();
  }
  const bool lame = m.has("mu") || m.has("lambda"), youngs = m.has("youngs") || m.has("poisson");
  if (lame && youngs) m.fail("give mu and lambda, or youngs and poisson, not both");
  try {
    if (youngs) {
      if (!m.has("youngs") || !m.has("poisson")) m.fail("youngs and poisson go together");
      s.params = lame_from_youngs(m.number("youngs", 0.0), m.number("poisson", 0.0));
    } else {
      if (lame && !(m.has("mu") && m.has("lambda")))
        m.fail(m.has("mu") ? "mu and lambda go together (got mu, no lambda)" : "mu and lambda go together (got lambda, no mu)");
      s.params = Lame{m.number("mu", s.params.mu), m.number("lambda", s.params.lambda)};
      validate(s.params);
    }
    s.reparametrize = m.boolean("reparametrize", s.reparametrize);
    (void)make_material(s.name, s.params, s.reparametrize);
  } catch (const SceneError&) {
    throw;
  } catch (const std::exception& e) {
    m.fail(e.what());
  }
  m.finish();
  return s;
}

MaterialSpec parse_material(Keys& top, const MaterialSpec& defaults) {
  MaterialSpec s = defaults;
  if (const json* mat = top.get("material")) static_cast<MaterialChoice&>(s) = parse_material_object(*mat, "material", top.file(), s);
  s.density = top.positive("density", s.density);
  return s;
}

}  // namespace snh::scene
