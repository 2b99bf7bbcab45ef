#include "mesh_commands.hpp"

#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "snh/fem/quality.hpp"
#include "snh/fem/rest_state.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/io/mesh_write.hpp"
#include "snh/mesh/surface.hpp"

namespace snh::cli {

void add_mesh_commands(CLI::App& app, int& exit_code) {
  auto in = std::make_shared<std::string>();
  CLI::App* info = app.add_subcommand(
      "info",
      "Reads and checks a volume mesh (.node/.ele, .mesh, .msh, .vtu), or a closed surface (.obj, .off, .ply, .stl) "
      "filled with tets by TetGen, and prints its counts, bounding box, volumes, an edge-ratio histogram and the problems "
      "found. Exit code 2 when the mesh cannot be used.");
  info->add_option("mesh", *in, "Mesh file")->required();
  info->callback([in, &exit_code]() {
    const MeshFile m = read_mesh(*in);
    const VolumeMesh& mesh = m.mesh;
    const Eigen::VectorXd vol = rest_volumes(compute_rest_state(mesh));
    const Eigen::VectorXd ratio = cell_edge_ratios(mesh);
    const Eigen::Vector3d lo = mesh.vertices.rowwise().minCoeff(), hi = mesh.vertices.rowwise().maxCoeff();
    std::cout << fmt::format("mesh {}: {}, {} vertices, {} cells, {} boundary triangles\n", *in, to_string(mesh.type),
                             mesh.vertex_count(), mesh.cell_count(), boundary_triangles(mesh).cols());
    std::cout << fmt::format("bounding box: ({:.6g}, {:.6g}, {:.6g}) .. ({:.6g}, {:.6g}, {:.6g}), size {:.6g} x {:.6g} x {:.6g}\n",
                             lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    std::cout << fmt::format("rest volume: total {:.6g}; per cell {:.6g} .. {:.6g}, mean {:.6g}\n", vol.sum(),
                             vol.minCoeff(), vol.maxCoeff(), vol.mean());
    const double edges[] = {1.0, 1.5, 2.0, 3.0, 5.0, 10.0};
    std::string hist;
    for (int b = 0; b < 6; ++b) {
      const double from = edges[b], to = b + 1 < 6 ? edges[b + 1] : std::numeric_limits<double>::infinity();
      const auto n = (ratio.array() >= from && ratio.array() < to).count();
      hist += fmt::format("{}{}: {}", b ? ", " : "", b + 1 < 6 ? fmt::format("{:g}-{:g}", from, to) : fmt::format(">= {:g}", from), n);
    }
    Eigen::Index worst = 0;
    ratio.maxCoeff(&worst);
    std::cout << fmt::format("edge ratio (longest / shortest edge of a cell): {}; worst {:.4g} (cell {})\n", hist,
                             ratio[worst], worst);
    std::cout << "problems: "
              << (m.reoriented ? fmt::format("{} inverted cell(s), re-oriented when used", m.reoriented) : "none") << "\n";
    exit_code = 0;
  });

  auto io = std::make_shared<std::pair<std::string, std::string>>();
  CLI::App* convert = app.add_subcommand(
      "convert", "Reads and checks a mesh (or a closed surface, filled with tets) and writes it in another format (.msh "
                 "Gmsh 4.1, .vtu, .mesh MEDIT); inverted cells are written re-oriented.");
  convert->add_option("in", io->first, "Input mesh (.node/.ele, .mesh, .msh, .vtu) or closed surface (.obj, .off, .ply, .stl)")
      ->required();
  convert->add_option("out", io->second, "Output mesh (.msh, .vtu, .mesh)")->required();
  convert->callback([io, &exit_code]() {
    check_writable_mesh_format(io->second);  // before reading: a bad output name fails at once
    const MeshFile m = read_mesh(io->first);
    write_mesh(io->second, m.mesh);
    std::cout << fmt::format("wrote {}: {} vertices, {} {}{}\n", io->second, m.mesh.vertex_count(), m.mesh.cell_count(),
                             m.mesh.type == CellType::tet4 ? "tets" : "hexes",
                             m.reoriented ? fmt::format(" ({} re-oriented)", m.reoriented) : "");
    exit_code = 0;
  });
}

}  // namespace snh::cli
