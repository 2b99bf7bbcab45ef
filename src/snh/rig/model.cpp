#include "snh/rig/model.hpp"

#include <algorithm>
#include <cctype>
#include <string>

#include <fmt/format.h>

#include "snh/rig/assimp.hpp"
#include "snh/rig/gltf.hpp"
#include "snh/rig/model_build.hpp"

namespace snh {

using rig_build::one_line;

namespace {
bool is_gltf(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".gltf" || ext == ".glb";
}
}  // namespace

std::string printable_name(std::string_view name) {
  std::string out;
  for (const char ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", c);
    else out += ch;
  }
  return out;
}

RiggedModel read_model(const std::filesystem::path& path) {
  RiggedModel m = is_gltf(path) ? read_gltf(path) : read_assimp(path);
  // Names reach the terminal, the header, the files and the report: control characters (ESC, BEL, NUL, a
  // newline) would act there instead of being read. They are written out as \xNN.
  for (Joint& j : m.skeleton.joints) j.name = printable_name(j.name);
  for (ModelPart& p : m.parts) p.name = printable_name(p.name);
  for (Clip& c : m.clips) c.name = printable_name(c.name);
  for (std::string& s : m.skipped) s = printable_name(s);
  for (std::string& s : m.notes) s = printable_name(s);
  return m;
}

int default_clip(const RiggedModel& model) {
  for (std::size_t c = 0; c < model.clips.size(); ++c)
    if (model.clips[c].duration() > 0.0 && model.clips[c].moves()) return static_cast<int>(c);
  return model.clips.empty() ? -1 : 0;
}

const Clip& find_clip(const RiggedModel& model, const std::string& name_or_index) {
  for (const Clip& c : model.clips)
    if (c.name == name_or_index) return c;
  if (!name_or_index.empty() && name_or_index.size() <= 9 &&
      std::all_of(name_or_index.begin(), name_or_index.end(), [](unsigned char c) { return c >= '0' && c <= '9'; })) {
    const std::size_t i = std::stoul(name_or_index);
    if (i < model.clips.size()) return model.clips[i];
  }
  std::string names;
  for (const Clip& c : model.clips) names += (names.empty() ? "" : ", ") + one_line(c.name);
  throw RigError(fmt::format("{}: no animation clip \"{}\" ({})", one_line(model.source.string()), one_line(name_or_index),
                             model.clips.empty() ? std::string("the model has no animation clip") : "clips: " + names));
}

}  // namespace snh
