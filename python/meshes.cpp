// snh.read_mesh, snh.write_mesh, snh.box: volume meshes as (vertices (n, 3), cells (m, 4 or 8), kind).
#include <filesystem>

#include <fmt/format.h>
#include <pybind11/stl/filesystem.h>

#include "common.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/io/mesh_write.hpp"
#include "snh/mesh/box.hpp"

namespace snh::py {

pyb::tuple mesh_tuple(const VolumeMesh& mesh) {
  // Eigen's 3 by #V and k by #C column-major storage is NumPy's (n, 3) and (m, k) row-major storage.
  Doubles vertices = new_array({mesh.vertex_count(), 3});
  std::copy(mesh.vertices.data(), mesh.vertices.data() + mesh.vertices.size(), vertices.mutable_data());
  pyb::array_t<std::int32_t> cells({mesh.cell_count(), static_cast<Eigen::Index>(mesh.cells.rows())});
  std::copy(mesh.cells.data(), mesh.cells.data() + mesh.cells.size(), cells.mutable_data());
  return pyb::make_tuple(vertices, cells, std::string(to_string(mesh.type)));
}

VolumeMesh mesh_of(const pyb::handle& vertices_obj, const pyb::handle& cells_obj) {
  VolumeMesh mesh;
  const Doubles vertices = real_array(vertices_obj, "vertices", {-1, 3});
  pyb::array cells_any = pyb::array::ensure(cells_obj);
  if (!cells_any) value_error("cells must be an array of vertex indices");
  const char kind = cells_any.dtype().kind();
  if (kind != 'i' && kind != 'u')
    value_error(fmt::format("cells must hold integer vertex indices, got dtype {}", std::string(pyb::str(cells_any.dtype()))));
  if (cells_any.ndim() != 2 || (cells_any.shape(1) != 4 && cells_any.shape(1) != 8))
    value_error(fmt::format("cells must have shape (m, 4) (tets) or (m, 8) (hexes), got {}", shape_text(cells_any)));
  const auto cells = pyb::array_t<std::int64_t, pyb::array::c_style | pyb::array::forcecast>::ensure(cells_any);
  const Eigen::Index n = vertices.shape(0), m = cells.shape(0), k = cells.shape(1);
  mesh.type = k == 4 ? CellType::tet4 : CellType::hex8;
  mesh.vertices = Eigen::Map<const Eigen::Matrix3Xd>(vertices.data(), 3, n);
  mesh.cells.resize(k, m);
  const std::int64_t* c = cells.data();
  for (Eigen::Index e = 0; e < m; ++e)
    for (Eigen::Index j = 0; j < k; ++j) {
      const std::int64_t v = c[e * k + j];
      if (v < 0 || v >= n)
        value_error(fmt::format("cells[{}, {}] = {} is not a vertex index (0 to {})", e, j, v, n - 1));
      mesh.cells(j, e) = static_cast<int>(v);
    }
  return mesh;
}

void add_meshes(pyb::module_& m) {
  using namespace pyb::literals;
  m.def("read_mesh", [](const std::filesystem::path& path) {
    MeshFile f;
    {
      pyb::gil_scoped_release release;
      f = read_mesh(path);
    }
    return mesh_tuple(f.mesh);
  }, "path"_a,
        "Reads a volume mesh by its extension (.node/.ele, .mesh, .msh, .vtu, or a closed surface .obj/.off/.ply/.stl "
        "through tetgen) and checks it as snh info does: (vertices (n, 3) float64, cells (m, 4 or 8) int32, kind 'tet4' or "
        "'hex8'); cells with negative rest volume come back re-oriented. ValueError with the reader's one-line message.");
  m.def("write_mesh", [](const std::filesystem::path& path, const pyb::handle& vertices, const pyb::handle& cells) {
    const VolumeMesh mesh = mesh_of(vertices, cells);
    check_writable_mesh_format(path);
    pyb::gil_scoped_release release;
    write_mesh(path, mesh);
  }, "path"_a, "vertices"_a, "cells"_a,
        "Writes a volume mesh by extension: .msh (Gmsh 4.1 ASCII), .vtu or .mesh (MEDIT), atomically. cells (m, 4) are tets, "
        "(m, 8) hexes (corner order of snh.box).");
  m.def("box", [](const std::string& element, int res, const std::string& tet_split) {
    if (element != "tet4" && element != "hex8" && element != "tet" && element != "hex")
      value_error(fmt::format("element must be tet4 or hex8, got '{}'", element));
    if (res < 1 || res > 400) value_error(fmt::format("resolution must be an integer from 1 to 400, got {}", res));
    if (tet_split != "paper" && tet_split != "mirrored")
      value_error(fmt::format("tet_split must be paper or mirrored, got '{}'", tet_split));
    const bool tets = element[0] == 't';
    return mesh_tuple(tets ? box_tets(res, tet_split == "paper" ? TetSplit::paper : TetSplit::mirrored) : box_hexes(res));
  }, "element"_a, "res"_a, "tet_split"_a = "paper",
        "The paper's box on [-1, 1]^3 with res cells per side: 6 res^3 tets (tetcli's mesh) or res^3 hexes (hexcli's), "
        "as (vertices, cells, kind).");
}

}  // namespace snh::py
