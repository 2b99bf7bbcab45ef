#pragma once
// "tissues" and "muscles" in a scene file (docs/scenes.md, docs/muscles.md): regions of the volume with their
// own material; a muscle's cells also have fibres (a direction per cell, their stiffness along it) that
// contract with its activation over time (docs/math.md §14). Parsed by setup/scene/parse_muscles.cpp, built
// on the body by setup/muscles.hpp.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "snh/material/fibre.hpp"
#include "snh/material/lame.hpp"

namespace snh {

/// A material given in a region (or the scene's "material").
struct MaterialChoice {
  std::string name = "stable_neo_hookean";
  Lame params{1.0, 10.0};
  bool reparametrize = false;
};

/// Where a region is: the cells whose rest centre lies in an axis-aligned box, inside a closed surface file,
/// or inside one of the flesh model's meshes (by name); or the cells a mesh file tags so.
struct RegionSpec {
  enum class Kind { box, mesh, model_mesh, tags };
  Kind kind = Kind::box;
  Eigen::AlignedBox3d box;
  std::filesystem::path file;  ///< mesh: .obj, .off, .ply or .stl (relative paths resolved against the scene file)
  std::string model_mesh;      ///< model_mesh: a mesh node's name in the flesh's model
  std::vector<long long> tags;  ///< tags: the mesh file's region tags (MeshFile::cell_tags) of its cells
};

/// A point of the rest pose: coordinates, a joint's rest position, or coordinates carried by a joint.
struct MusclePoint {
  std::string joint;                   ///< empty: a fixed point
  std::optional<Eigen::Vector3d> point;  ///< unset: the joint's rest position
};

struct ActivationKey {
  double time = 0.0;
  double value = 0.0;  ///< in [0, 1]
};

/// Activation that follows the skeleton: a = clamp(gain · (1 − L/L₀), 0, max), L the distance between the
/// two points as their joints carry them, L₀ at rest: it rises as the line shortens.
struct LineOfAction {
  MusclePoint from, to;
  double gain = 1.0;
  double max = 1.0;
};

struct MuscleSpec {
  std::string name;
  bool muscle = true;                       ///< false: an entry of "tissues" (no fibres)
  RegionSpec region;
  std::optional<MaterialChoice> material;   ///< unset: the scene's material
  std::string bone;                         ///< a tissue bound whole to this joint (kinematic); empty: none
  // Fibres (muscles):
  enum class Field { constant, harmonic, file };
  Field field = Field::constant;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  ///< constant: the fibres' direction (unit)
  MusclePoint origin, insertion;            ///< harmonic: the field runs from 0 at the origin to 1 at the insertion
  /// harmonic: the ends are the region's vertices within this of the nearest one to each point (unset: a
  /// tenth of the distance from origin to insertion)
  std::optional<double> reach;
  /// file: a text file of one direction "ax ay az" per cell of the volume, in cell order (relative paths
  /// resolved against the scene file); the region's cells take theirs
  std::filesystem::path fibre_file;
  FibreModel fibre_model = FibreModel::signed_arap;
  std::optional<double> fibre_stiffness;    ///< unset: the region's shear modulus mu
  double contraction = 0.25;                ///< γ in [0, 1): the fibres shorten to 1 − γ a
  std::vector<ActivationKey> keys;          ///< activation over time (piecewise linear; none and no line: 0)
  std::optional<LineOfAction> line;
};

}  // namespace snh
