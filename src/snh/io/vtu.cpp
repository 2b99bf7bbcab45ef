#include "snh/io/vtu.hpp"

#include <iterator>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/io/lexer.hpp"

namespace snh {

void write_vtu(const std::filesystem::path& path, const VolumeMesh& mesh, const Eigen::Matrix3Xd& positions,
               const std::vector<std::pair<std::string, Eigen::Matrix3Xd>>& point_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& cell_data,
               const std::vector<std::pair<std::string, Eigen::VectorXd>>& point_scalars) {
  // VTK_HEXAHEDRON walks the bottom face around; VolumeMesh has c2 = c0 + ŷ, c3 = c0 + x̂ + ŷ.
  static constexpr int kHexToVtk[8] = {0, 1, 3, 2, 4, 5, 7, 6};
  const int npc = nodes_per_cell(mesh.type);
  const int vtk_type = mesh.type == CellType::tet4 ? 10 : 12;
  write_atomically(path, [&](std::ostream& out) {
    fmt::memory_buffer b;
    auto o = std::back_inserter(b);
    fmt::format_to(o, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
                      "<UnstructuredGrid>\n<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n",
                   positions.cols(), mesh.cell_count());
    fmt::format_to(o, "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (Eigen::Index v = 0; v < positions.cols(); ++v)
      fmt::format_to(o, "{:.10g} {:.10g} {:.10g}\n", positions(0, v), positions(1, v), positions(2, v));
    fmt::format_to(o, "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
      for (int a = 0; a < npc; ++a)
        fmt::format_to(o, "{}{}", a ? " " : "", mesh.cells(mesh.type == CellType::hex8 ? kHexToVtk[a] : a, c));
      fmt::format_to(o, "\n");
    }
    fmt::format_to(o, "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) fmt::format_to(o, "{}\n", (c + 1) * npc);
    fmt::format_to(o, "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) fmt::format_to(o, "{}\n", vtk_type);
    fmt::format_to(o, "</DataArray>\n</Cells>\n<PointData>\n");
    for (const auto& [name, field] : point_data) {
      fmt::format_to(o, "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n", name);
      for (Eigen::Index v = 0; v < field.cols(); ++v)
        fmt::format_to(o, "{:.10g} {:.10g} {:.10g}\n", field(0, v), field(1, v), field(2, v));
      fmt::format_to(o, "</DataArray>\n");
    }
    for (const auto& [name, field] : point_scalars) {
      fmt::format_to(o, "<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">\n", name);
      for (Eigen::Index v = 0; v < field.size(); ++v) fmt::format_to(o, "{:.10g}\n", field[v]);
      fmt::format_to(o, "</DataArray>\n");
    }
    fmt::format_to(o, "</PointData>\n<CellData>\n");
    for (const auto& [name, field] : cell_data) {
      fmt::format_to(o, "<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">\n", name);
      for (Eigen::Index c = 0; c < field.size(); ++c) fmt::format_to(o, "{:.10g}\n", field[c]);
      fmt::format_to(o, "</DataArray>\n");
    }
    fmt::format_to(o, "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    out.write(b.data(), static_cast<std::streamsize>(b.size()));
  });
}

void write_pvd(const std::filesystem::path& path, const std::vector<std::pair<double, std::string>>& frames) {
  write_atomically(path, [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n<Collection>\n";
    for (const auto& [t, file] : frames)
      out << fmt::format("<DataSet timestep=\"{:g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t, file);
    out << "</Collection>\n</VTKFile>\n";
  });
}

std::vector<std::pair<double, std::string>> read_pvd(const std::filesystem::path& path) {
  const std::string text = detail::read_all(path);
  std::vector<std::pair<double, std::string>> out;
  for (std::size_t at = text.find("<DataSet"); at != std::string::npos; at = text.find("<DataSet", at + 1)) {
    const std::string_view tag = std::string_view(text).substr(at, text.find('>', at) - at);
    const std::string file = detail::xml_attribute(tag, "file"), time = detail::xml_attribute(tag, "timestep");
    double t = static_cast<double>(out.size());
    if (!time.empty()) {
      try {
        t = std::stod(time);
      } catch (const std::exception&) {
        throw MeshError(fmt::format("{}: DataSet {}: timestep \"{}\" is not a number", path.string(), out.size(), time));
      }
    }
    if (file.empty()) throw MeshError(fmt::format("{}: DataSet {} has no file", path.string(), out.size()));
    out.emplace_back(t, file);
  }
  if (out.empty()) throw MeshError(fmt::format("{}: lists no frames", path.string()));
  return out;
}

}  // namespace snh
