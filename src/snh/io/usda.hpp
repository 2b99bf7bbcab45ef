#pragma once
// USD ASCII stages (docs/design.md): triangle meshes whose points are time-sampled per frame, written
// following the .usda grammar (a `#usda 1.0` layer with stage metadata, `def Xform` and `def Mesh` prims,
// `point3f[] points.timeSamples`, with `extent` and, where given, `normals` per frame and the texture
// coordinates `primvars:st`), which usdview, Blender and Houdini open.
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace snh {

struct UsdMesh {
  std::string name;                    ///< the prim's name: a letter or '_' then letters, digits, '_'
  Eigen::Matrix3Xi triangles;          ///< 3 by #F, 0-based, counter-clockwise seen from outside
  std::vector<Eigen::Matrix3Xd> frames;  ///< the points (3 by #V) at time codes 0, 1, 2, …
  std::vector<Eigen::Matrix3Xd> normals; ///< per frame, unit vertex normals (3 by #V); empty: none written
  Eigen::Matrix2Xd uv;                   ///< texture coordinates per vertex (2 by #V, origin bottom left); empty: none
  /// Per frame, whether it is a result: where one is false, the mesh gets `custom bool snh:converged` sampled
  /// at every time code (a frame that did not converge, which a run went past, is marked false). Empty: none.
  std::vector<bool> converged;
};

/// Writes the stage atomically: one Xform prim `root` (the default prim) holding each mesh, time codes 0 …
/// frames − 1 played at `frames_per_second`, with the stage's metersPerUnit and upAxis ('Y' or 'Z', as USD
/// has them). Throws std::invalid_argument for a bad prim name, meshes without frames, frames of differing
/// sizes, a non-finite point, a unit that is not a positive number or another axis; WriteError when the
/// file cannot be written.
void write_usda(const std::filesystem::path& path, const std::string& root, const std::vector<UsdMesh>& meshes,
                double frames_per_second, double meters_per_unit = 1.0, char up_axis = 'Y');

}  // namespace snh
