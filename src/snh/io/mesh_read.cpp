#include "snh/io/mesh_read.hpp"

#include <string>

#include <fmt/format.h>

#include "snh/io/gmsh.hpp"
#include "snh/io/input_file.hpp"
#include "snh/io/medit.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/io/tetgen.hpp"

namespace snh {

MeshFile read_mesh_file(const std::filesystem::path& path) {
  // What is there first (/dev/zero, a directory), then the format its name gives.
  if (const std::string problem = input_file_problem(path, "mesh file"); !problem.empty()) throw MeshError(problem);
  const std::string ext = path.extension().string();
  if (ext == ".node" || ext == ".ele") {
    std::filesystem::path node = path, ele = path;
    node.replace_extension(".node");
    ele.replace_extension(".ele");
    return read_tetgen(node, ele);
  }
  if (ext == ".mesh") return read_medit(path);
  if (ext == ".msh") return read_gmsh(path);
  if (ext == ".vtu") return read_vtu(path);
  if (is_surface_file(path)) return tetrahedralize(read_surface(path), path);
  throw MeshError(fmt::format("{}: unknown mesh format '{}' (known: .node/.ele, .mesh, .msh, .vtu; surfaces .obj, .off, "
                              ".ply, .stl)",
                              path.string(), ext));
}

MeshFile read_mesh(const std::filesystem::path& path) {
  MeshFile m = read_mesh_file(path);
  check_mesh(m, path);
  return m;
}

}  // namespace snh
