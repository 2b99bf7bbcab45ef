#include "snh/setup/scene/sections.hpp"

namespace snh::scene {

MeshSpec parse_mesh(Keys& top, const std::filesystem::path& source) {
  MeshSpec s;
  const json* mesh = top.get("mesh");
  if (!mesh) return s;
  Keys m(*mesh, "mesh", top.file());
  const json* box = m.get("box");
  const json* mesh_file = m.get("file");
  if ((box != nullptr) == (mesh_file != nullptr)) m.fail("give exactly one of box or file");
  if (mesh_file) {
    if (!mesh_file->is_string() || mesh_file->get<std::string>().empty()) m.fail("expected a file name", "file");
    const std::filesystem::path f = mesh_file->get<std::string>();
    s.file = f.is_absolute() ? f : source.parent_path() / f;
  } else {
    Keys b(*box, "mesh.box", top.file());
    s.element = b.choice("element", "hex", {"tet", "hex"}) == "tet" ? CellType::tet4 : CellType::hex8;
    s.resolution = static_cast<int>(b.integer("res", s.resolution, 1, 400));
    s.tet_split = b.choice("tet_split", "paper", {"paper", "mirrored"}) == "mirrored" ? TetSplit::mirrored : TetSplit::paper;
    s.min = b.vec3("min").value_or(s.min);
    s.max = b.vec3("max").value_or(s.max);
    if (!(s.min.array() < s.max.array()).all()) b.fail("min must be below max on every axis");
    b.finish();
  }
  m.finish();
  return s;
}

}  // namespace snh::scene
