#include "snh/io/mesh_write.hpp"

#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "snh/io/vtu.hpp"

namespace snh {

void check_writable_mesh_format(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  if (ext != ".msh" && ext != ".vtu" && ext != ".mesh")
    throw std::invalid_argument(fmt::format("{}: cannot write '{}' meshes (known: .msh, .vtu, .mesh)", path.string(), ext));
}

void write_mesh(const std::filesystem::path& path, const VolumeMesh& mesh) {
  check_writable_mesh_format(path);
  const std::string ext = path.extension().string();
  if (ext == ".msh") write_msh(path, mesh);
  else if (ext == ".mesh") write_medit(path, mesh);
  else write_vtu(path, mesh, mesh.vertices, {}, {});
}

}  // namespace snh
