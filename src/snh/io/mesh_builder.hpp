#pragma once
// Internal to the volume-mesh readers (io/): vertices and cells collected as a file is read, the file's
// own vertex ids mapped to indices, into a MeshFile.
#include <optional>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>

#include "snh/io/lexer.hpp"
#include "snh/io/mesh_file.hpp"

namespace snh::detail {

/// Collects vertices and cells of one type; maps file vertex ids to indices.
struct MeshBuilder {
  std::vector<double> xyz;
  std::unordered_map<long long, int> index_of;  ///< file id → index (formats with arbitrary ids)
  std::optional<CellType> type;
  std::vector<int> cells;
  std::vector<int> lines;
  std::vector<long long> tags;  ///< per cell, its region tag (0 where the file gives none)

  /// Adds the vertex with file id `id`; an id given twice is an error on lx's current line.
  void vertex(Lexer& lx, long long id, double x, double y, double z) {
    if (!index_of.emplace(id, static_cast<int>(xyz.size() / 3)).second) lx.fail(fmt::format("vertex {} is defined twice", id));
    xyz.insert(xyz.end(), {x, y, z});
  }
  /// Adds a cell of type `t` from file ids (already in VolumeMesh corner order), read from `line`, with its
  /// region tag.
  void cell(Lexer& lx, CellType t, const std::vector<long long>& ids, int line, long long tag = 0) {
    if (type && *type != t)
      lx.fail(fmt::format("a mesh of both tets and hexes is not supported (this {} follows {})", t == CellType::tet4 ? "tet" : "hex",
                          *type == CellType::tet4 ? "tets" : "hexes"),
              line);
    type = t;
    for (long long id : ids) {
      const auto it = index_of.find(id);
      if (it == index_of.end()) lx.fail(fmt::format("cell refers to vertex {}, which does not exist", id), line);
      cells.push_back(it->second);
    }
    lines.push_back(line);
    tags.push_back(tag);
  }
  /// The mesh read; no cell at all is an error on lx's current line.
  MeshFile finish(const Lexer& lx) {
    if (!type) lx.fail("the file has no tetrahedra or hexahedra");
    MeshFile m;
    m.mesh.type = *type;
    m.mesh.vertices = Eigen::Map<const Eigen::Matrix3Xd>(xyz.data(), 3, static_cast<Eigen::Index>(xyz.size() / 3));
    const int n = nodes_per_cell(*type);
    m.mesh.cells = Eigen::Map<const Eigen::MatrixXi>(cells.data(), n, static_cast<Eigen::Index>(cells.size() / n));
    m.cell_lines = lines;
    m.cell_tags = tags;
    return m;
  }
};

}  // namespace snh::detail
