#include <limits>
#include <numbers>

#include "snh/setup/scene/sections.hpp"

namespace snh::scene {
namespace {

/// Start and end of a motion: [start, end], end later than start.
template <class M>
void read_timing(Keys& k, double end_time, M& m) {
  m.start = k.non_negative("start", 0.0);
  m.end = k.non_negative("end", end_time);
  if (!(m.end > m.start)) k.fail(fmt::format("end ({:g}) must be later than start ({:g})", m.end, m.start));
}

}  // namespace

Motion parse_motion(const json& j, const std::string& path, const std::string& file, double end_time) {
  Keys k(j, path, file);
  const std::string type = k.choice("type", "", {"translate", "rotate", "scale"});
  if (type.empty()) k.fail("needs a type (translate, rotate or scale)");
  Motion motion;
  if (type == "translate") {
    Translate m;
    read_timing(k, end_time, m);
    const auto by = k.vec3("by");
    if (!by) k.fail("translate needs by: [dx, dy, dz]");
    m.by = *by;
    motion = m;
  } else if (type == "rotate") {
    Rotate m;
    read_timing(k, end_time, m);
    m.center = k.vec3("center");
    const auto axis = k.vec3("axis");
    if (!axis || axis->norm() == 0.0) k.fail("rotate needs a non-zero axis: [ax, ay, az]");
    m.axis = axis->normalized();
    m.radians = k.number("degrees", 0.0) * std::numbers::pi / 180.0;
    motion = m;
  } else {
    Scale m;
    read_timing(k, end_time, m);
    m.center = k.vec3("center");
    const auto f = k.vec3("factors");
    if (!f || (f->array() <= 0.0).any()) k.fail("scale needs factors: three numbers > 0");
    m.factors = *f;
    motion = m;
  }
  k.finish();
  return motion;
}

Selection parse_selection(Keys& k) {
  Selection s;
  const json* region = k.get("region");
  const json* indices = k.get("indices");
  if ((region != nullptr) == (indices != nullptr)) k.fail("give exactly one of region or indices");
  if (region) {
    Keys r(*region, k.path("region"), k.file());
    const auto lo = r.vec3("min"), hi = r.vec3("max");
    if (!lo || !hi) r.fail("needs min and max");
    if ((lo->array() > hi->array()).any()) r.fail("min must not exceed max");
    r.finish();
    s.region = Eigen::AlignedBox3d(*lo, *hi);
  } else {
    if (!indices->is_array() || indices->empty()) k.fail("expected a non-empty array of vertex indices", "indices");
    for (const auto& i : *indices) {
      if (!i.is_number_integer() || i.get<long long>() < 0 || i.get<long long>() > std::numeric_limits<int>::max())
        k.fail("expected vertex indices (integers >= 0), got " + i.dump(), "indices");
      s.indices.push_back(i.get<int>());
    }
  }
  return s;
}

std::vector<PinSpec> parse_pins(Keys& top, double end_time) {
  std::vector<PinSpec> out;
  const json* pins = top.get("pins");
  if (!pins) return out;
  if (!pins->is_array()) top.fail("expected an array of pin sets", "pins");
  for (std::size_t i = 0; i < pins->size(); ++i) {
    const std::string path = fmt::format("pins[{}]", i);
    Keys p((*pins)[i], path, top.file());
    PinSpec pin;
    pin.select = parse_selection(p);
    if (const json* axes = p.get("axes")) {
      if (!axes->is_string() || axes->get<std::string>().empty() ||
          axes->get<std::string>().find_first_not_of("xyz") != std::string::npos)
        p.fail("expected the held coordinates as letters, e.g. \"xyz\" or \"x\", got " + axes->dump(), "axes");
      for (int a = 0; a < 3; ++a) pin.axes[a] = axes->get<std::string>().find(char('x' + a)) != std::string::npos;
    }
    if (const json* motions = p.get("motion")) {
      if (!motions->is_array()) p.fail("expected an array of motions", "motion");
      for (std::size_t k = 0; k < motions->size(); ++k)
        pin.motions.push_back(parse_motion((*motions)[k], fmt::format("{}.motion[{}]", path, k), top.file(), end_time));
    }
    p.finish();
    out.push_back(std::move(pin));
  }
  return out;
}

}  // namespace snh::scene
