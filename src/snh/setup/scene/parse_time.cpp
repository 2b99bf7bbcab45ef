#include "snh/setup/scene/sections.hpp"

namespace snh::scene {

TimeSpec parse_time(Keys& top) {
  TimeSpec s;
  s.integrator = *integrator_named(top.choice("integrator", "backward_euler", {"backward_euler", "bdf2", "tr_bdf2", "quasi_static"}));
  s.dt = top.positive("dt", s.dt);
  // Asked for either way (so that an unknown key's message lists them), kept where given.
  const double end_time = top.positive("end_time", TimeSpec::default_end_time);
  const auto frames = static_cast<int>(top.integer("frames", TimeSpec::default_frames, 1, 100000));
  if (top.has("end_time")) s.end_time = end_time;
  if (top.has("frames")) s.frames = frames;
  return s;
}

ForceSpec parse_forces(Keys& top) {
  ForceSpec s;
  s.gravity = top.vec3("gravity").value_or(s.gravity);
  if (const json* damping = top.get("damping")) {
    Keys d(*damping, "damping", top.file());
    s.mass_damping = d.non_negative("mass", s.mass_damping);
    s.stiffness_damping = d.non_negative("stiffness", s.stiffness_damping);
    d.finish();
  }
  return s;
}

}  // namespace snh::scene
