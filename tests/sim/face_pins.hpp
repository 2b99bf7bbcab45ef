#pragma once
// Pinned faces for the tests (tests only): the vertices of a mesh whose coordinate `axis` equals `value`
// exactly (a box mesh's face), held by scripted motions.
#include <memory>
#include <string>
#include <vector>

#include "snh/mesh/volume_mesh.hpp"
#include "snh/sim/kinematics.hpp"

namespace snh {

inline KinematicSet face_pins(const VolumeMesh& m, int axis, double value, std::vector<Motion> motions, std::string name) {
  KinematicSet set;
  set.name = std::move(name);
  for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
    if (m.vertices(axis, v) == value) set.vertices.push_back(static_cast<int>(v));
  set.provider = std::make_shared<ScriptedMotion>(m.vertices(Eigen::all, set.vertices), std::move(motions));
  return set;
}

}  // namespace snh
