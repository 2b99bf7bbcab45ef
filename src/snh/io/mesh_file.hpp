#pragma once
// What every volume-mesh reader (io/tetgen, io/medit, io/gmsh, io/vtu) returns, and the error each throws.
#include <stdexcept>
#include <vector>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// A mesh file that cannot be used: "FILE:LINE: what is wrong" (or "FILE: element N: ...").
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct MeshFile {
  VolumeMesh mesh;
  std::vector<int> cell_lines;  ///< the line each cell was read from (0 where not known)
  int reoriented = 0;           ///< inverted rest elements turned the right way round by check_mesh
  /// Per cell, the file's region tag: a MEDIT reference, a Gmsh 2.2 element's first (physical) tag or a
  /// Gmsh 4.1 block's entity tag, a TetGen region attribute; empty for a format without (VTU).
  std::vector<long long> cell_tags;
};

}  // namespace snh
