#include "snh/setup/scene.hpp"

#include <fstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/input_file.hpp"
#include "snh/setup/scene/sections.hpp"

namespace snh {

Scene parse_scene(const nlohmann::json& j, const std::filesystem::path& source) {
  Scene s;
  s.source = source;
  scene::Keys top(j, "", source.string());
  s.flesh = scene::parse_flesh(top, source);
  s.mesh = scene::parse_mesh(top, source);
  // The paper's defaults for flesh: quasi-static, E = 100 kPa and nu = 0.488, the density of water.
  MaterialSpec material;
  if (s.flesh) {
    material.params = lame_from_youngs(FleshSpec::youngs, FleshSpec::poisson);
    material.density = FleshSpec::density;
  }
  s.material = scene::parse_material(top, material);
  s.time = scene::parse_time(top);
  if (s.flesh && !top.has("integrator")) s.time.integrator = Integrator::quasi_static;
  s.forces = scene::parse_forces(top);
  s.pins = scene::parse_pins(top, s.time.end_time.value_or(TimeSpec::default_end_time));
  s.initial = scene::parse_initial(top);
  s.solver = scene::parse_solver(top);
  s.contact = scene::parse_contact(top, source, s.time.end_time.value_or(TimeSpec::default_end_time));
  s.muscles = scene::parse_muscles(top, source, s.flesh.has_value());
  s.output = scene::parse_output(top, source);
  top.finish();
  s.settings = j.dump();  // object keys sorted: the same text for the same scene
  return s;
}

Scene load_scene(const std::filesystem::path& file) {
  if (const std::string problem = input_file_problem(file, "scene file"); !problem.empty()) throw SceneError(problem);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw SceneError(fmt::format("{}: cannot open the scene file", file.string()));
  // Read up to the first NUL byte, which JSON text never holds: a NUL-padded file fails having read about
  // as much as its text.
  std::string text;
  for (std::size_t old = 0;; old = text.size()) {
    text.resize(old + (1 << 20));
    in.read(text.data() + old, 1 << 20);
    text.resize(old + static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw SceneError(fmt::format("{}: cannot read the scene file", file.string()));
    if (text.size() == old || text.find('\0', old) != std::string::npos) break;
  }
  return parse_scene(read_scene_json(text, file.string()), file);
}

}  // namespace snh
