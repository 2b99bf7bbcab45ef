#pragma once
// Skeleton-driven flesh (docs/design.md setup/, docs/flesh.md; the paper's Figure 1 workflow): a rigged model's closed render
// surface is filled with a volume (a hexahedral lattice or TetGen's tets), the volume vertices inside the
// bones' capsules follow their bones exactly (a kinematic set whose targets come from the animation), the
// rest of the flesh is solved, and the render surface, embedded in the volume, follows it. Linear blend
// skinning of the same surface with the model's own weights is the comparison.
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "snh/embed/embedding.hpp"
#include "snh/fem/term.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/mesh/volume_mesh.hpp"
#include "snh/rig/animation.hpp"
#include "snh/rig/bind_pose.hpp"
#include "snh/rig/bones.hpp"
#include "snh/rig/model.hpp"
#include "snh/rig/normals.hpp"
#include "snh/sim/kinematics.hpp"

namespace snh {

enum class FleshVolume { lattice, tets };

/// What becomes of bound vertices in cells that span a joint (a cell holding vertices of two joints' bones):
/// `hard` (the default) keeps them bound (HOBAK's binding: the cell is then forced by two rigid motions, and
/// a sharply bent joint can stall Newton next to it); `free` releases them to the solve; `soft` releases
/// them from the hard binding and binds them softly (weight 1) to their bones.
enum class JointCells { soft, free, hard };
[[nodiscard]] inline const char* to_string(JointCells j) {
  return j == JointCells::soft ? "soft" : j == JointCells::free ? "free" : "hard";
}

/// Keyframed rotations shared by one or more joints: at each time a rotation relative to the joint's rest
/// rotation, about the joint's own axes (animation.hpp JointKeys), slerped between keys.
struct KeyframeSpec {
  std::vector<std::string> joints;
  std::vector<double> times;                  ///< strictly increasing
  std::vector<Eigen::Quaterniond> rotations;  ///< one per time
};

/// A capsule radius set by the user for every bone of a joint.
struct BoneRadius {
  std::string joint;
  double radius = 0.0;
};

/// "flesh" in a scene file, or `snh flesh`'s options.
struct FleshSpec {
  std::filesystem::path model;               ///< .glb or .gltf (a scene's relative path resolved against it)
  std::string animation;                     ///< the model's clip, by name or index; empty: `keyframes`, else clip 0
  std::vector<KeyframeSpec> keyframes;
  FleshVolume volume = FleshVolume::lattice;
  /// Lattice cubes (tets: cube-sized tets) along the longest side; 0: chosen from the bones (flesh_resolution).
  int resolution = 0;
  double cell_size = 0.0;                    ///< > 0: the cubes' edge in model units instead of a resolution
  std::vector<BoneRadius> radii;
  /// Scales every default capsule radius (half the mean distance from the bone to its nearest skin); radii
  /// given per joint in `radii` are taken as given. Below 1 where the capsules of neighbouring bones would
  /// press their bound flesh into each other as a joint bends (a fist's knuckles, at fine resolutions).
  double radius_scale = 1.0;
  /// Soft binding: the volume vertices within `soft_shell` (model units; 0: none) outside a capsule are
  /// pulled toward where their bone carries them by springs of stiffness soft_stiffness × E × h × weight
  /// (E Young's modulus, h the cell size: 1 is about as stiff as one cell of flesh; weight fading from 1 at
  /// the capsule to 0 at the shell's edge).
  double soft_shell = 0.0;
  double soft_stiffness = 1.0;
  JointCells joint_cells = JointCells::hard;
  /// A lattice cube whose material the skin separates (fingers closer than a cube) becomes a cell per piece,
  /// joined only where the material is (the virtual node algorithm); false: one cell per cube, pieces glued.
  bool split_cells = true;
  /// false: meshes whose skins share no joint and no vertex are separate solids, each held only by its own
  /// joints' bones, so that parts overlapping at rest (a hand sunk into a thigh) are not fused; true: all the
  /// meshes make one solid.
  bool join_meshes = false;
  // Defaults of a flesh run (the paper's: nu = 0.488) where the scene or command gives none:
  static constexpr double youngs = 1e5, poisson = 0.488;  ///< Pa; with quasi-static bones only nu matters
  static constexpr double density = 1000.0;               ///< kg/m³ (dynamics)
  /// Frames per second of animation: a scene without "frames" runs frames at t = i / fps up to end_time
  /// rounded up to a whole frame.
  double fps = 24.0;
};

/// The flesh of a rigged model, ready to simulate.
struct Flesh {
  RiggedModel model;
  Clip clip;                                 ///< the animation that drives the bones
  BindPose bind;                             ///< how the model was placed at its bind pose (model is placed)
  std::vector<Eigen::Affine3d> bind_world;   ///< the joints' frames at the bind pose (bind.joints): the bones'
                                             ///< motion at time t is joint_world(t) · bind_world⁻¹
  VolumeMesh volume;
  double cell_size = 0.0;                    ///< the lattice's cube edge (tets: the edge of the cube whose volume bounds a tet)
  int resolution = 0;                        ///< cubes along the longest side: given, from cell_size, or chosen
  std::string resolution_reason;             ///< why this resolution (one clause for the header)
  int split_cubes = 0;                       ///< lattice cubes the surface splits into pieces (a cell per piece)
  int copied_vertices = 0;                   ///< vertices at a grid node with more than one (the split cubes' nodes)
  /// The solids the meshes make (lattice): per solid its meshes' names, joined by " + " (one: all in one).
  std::vector<std::string> solids;
  std::vector<int> solid_of_point;           ///< per model vertex its solid (lattice)
  std::vector<int> solid_of_volume_vertex;   ///< per volume vertex its solid (a seam's: the first); empty when one solid
  int seam_vertices = 0;                     ///< skin vertices (welded) shared by two solids: glued there
  double volume_of_cells = 0.0;              ///< the volume mesh's rest volume
  double surface_volume = 0.0;               ///< enclosed by the render surface at rest (its magnitude; for an
                                             ///< open surface the volume its triangles and the origin span)
  EdgeCounts edges;                          ///< of the welded surface: open edges are holes, tolerated
  bool inside_out = false;                   ///< the surface's signed volume is negative (triangles face inwards)
  NormalGroups normal_groups;                ///< the skin's vertices that share a normal in the frames written
  Embedding embedding;                       ///< the model's vertices (its order) in the volume
  std::vector<Bone> bones;                   ///< with their capsule radii
  Binding binding;                           ///< volume vertices that follow bones
  /// Parts of the volume that held no bone's capsule, bound whole to the joint their skin is weighted to
  /// most (a prop or an eye that only its joint carries): "N vertices to JOINT" each.
  std::vector<std::string> free_parts;
  std::vector<int> bound_per_bone;
  Binding released;                          ///< vertices in a capsule released at the joints (joint_cells)
  SoftBinding soft;                          ///< volume vertices pulled toward bones: the shell's, and the
                                             ///< released ones when joint_cells is soft
};

/// The resolution a flesh gets when neither a resolution nor a cell size is given: cells no wider than 2/√3 of
/// the thinnest capsule among the bones nearest to some of the skin (a lattice node then lies within every such
/// capsule, which then binds flesh), at least 16; at most the resolution whose cells, estimated as twice the
/// skin's volume over h³, stay under 20 000 (a default run takes seconds; more is asked for by name). `reason`
/// says which rule chose it.
///   reach  bone_reach of the bones and the skin (surface), which says which bones are closest to some skin
[[nodiscard]] int flesh_resolution(const std::vector<Bone>& bones, const BoneReach& reach, const Eigen::Matrix3Xd& surface,
                                   double surface_volume, std::string& reason);

/// Reads the model and builds its flesh. Throws RigError (bad model, a surface that is not closed: the open
/// and non-manifold edge counts; a joint of the spec that the model lacks), MeshError (tetgen failed) or
/// std::invalid_argument (a bone whose user-set radius binds nothing, nothing bound at all), one line each
/// naming `where` (the scene file or the command). A lattice whose run cannot fit in memory with the linear
/// solver `solver` (a registry name, "auto": chosen by size) is refused before it is built
/// (MemoryEstimateError), as the run would be refused after (check_memory), from the fewest cells the skin's
/// volume needs.
[[nodiscard]] Flesh build_flesh(const FleshSpec& spec, const std::string& where, std::string_view solver = "auto");

/// The bones' kinematic set: the bound vertices, moved rigidly with their bones' joints by the clip.
[[nodiscard]] KinematicSet bone_kinematics(std::shared_ptr<const Flesh> flesh);

/// Where the bones press their bound flesh into each other: two volume vertices bound to bones of different
/// joints, at least two cells apart at rest, carried closer than half a cell. The flesh between them then keeps
/// under a quarter of its rest thickness and (at ν near ½) cannot keep its volume: it turns inside out, and
/// Newton pays for it. It happens where the capsules of neighbouring bones overlap as a joint bends (a fist's
/// knuckles), and shows at fine resolutions, whose cells resolve the squeezed layer. `frame` < 0: nowhere.
struct PressedFlesh {
  int frame = -1;             ///< index into the times given: the frame with the smallest ratio
  double time = 0.0;
  int bone_a = -1, bone_b = -1;
  double rest = 0.0, closest = 0.0;  ///< the pair's distance at rest and in that frame (model units)
  int frames = 0;             ///< how many of the times press flesh so
};
///   times  the run's frame times (the bones' poses checked)
[[nodiscard]] PressedFlesh pressed_flesh(const std::shared_ptr<const Flesh>& flesh, const std::vector<double>& times);

/// The soft binding's springs (null without softly bound vertices): stiffness soft_stiffness × youngs ×
/// cell size × weight per vertex, toward the vertex's rest position carried rigidly by its bone's joint.
[[nodiscard]] std::shared_ptr<Term> soft_binding_term(std::shared_ptr<const Flesh> flesh, double soft_stiffness,
                                                      double youngs);

/// A frame per volume vertex that carries the flesh along with the bones (SimulationSetup::carrier): the
/// joints' motions from the bind pose, world(t)·bind⁻¹, blended with the skin weights of the model vertex nearest
/// to the volume vertex at rest (linear blend skinning of the volume, used only to predict).
[[nodiscard]] std::function<void(double t, std::vector<Eigen::Matrix<double, 3, 4>>& frames)> flesh_carrier(
    std::shared_ptr<const Flesh> flesh);

/// The render surface as contact sees it: the model's welded, closed surface (surface_triangles over its
/// welded vertices), each welded vertex embedded in the volume as its first model vertex is (points: k by
/// #welded cells' vertices and weights, k = 8 in a lattice, 4 in tets; points.apply(x) places them).
struct EmbeddedSurface {
  Eigen::Matrix3Xi triangles;
  Embedding points;
};
[[nodiscard]] EmbeddedSurface contact_surface(const Flesh& flesh);

/// Contact's defaults for flesh. d̂: a quarter of the render surface's mean edge length at rest (contact
/// acts at the scale of the surface's own detail, well inside a cell), but at most half the surface's
/// smallest distance at rest (so that no pair is in range at the start: the rest pose stays the
/// solution of the first frame). κ = E h / d̂² (E Young's modulus, h
/// the cell size): the barrier's curvature near d̂/2 is then of the order of one cell's stiffness E h (its
/// Hessian in distance is κ d̂² times an O(1) factor), so a quasi-static solve sees neither a negligible
/// barrier (pairs squeezed to tiny distances, ill-conditioned) nor one that dominates the flesh. IPC's
/// automatic κ needs masses and a time step, which quasi-static flesh has not.
[[nodiscard]] double flesh_contact_dhat(const Flesh& flesh);
[[nodiscard]] double flesh_contact_stiffness(const Flesh& flesh, double youngs, double dhat);

/// The bones' capsules as moving colliders (one ShapeColliderTerm per bone: a capsule, or a sphere for a
/// point bone, carried by its joint) against the skin that is not bound to them: the render surface's points
/// (contact_surface, embedded in the volume) that are
///   - not skinned to the bone's joint, nor to that joint's parent or the bone's child joint (the flesh that
///     folds around the capsule's ends as those joints bend: the capsules of a bent joint overlap it);
///   - not hanging on the bone (no vertex of the point's cell bound to it, hard or released) and not carried
///     by bones alone (a cell all hard-bound: the barrier could not hold such a point off);
///   - farther than 2 d̂ outside the capsule at rest (nothing in range at the start: the rest state stays the
///     solution of the first frame; where a capsule pokes out of the skin, the skin next to it is left out).
/// A finger's skin pressed onto another finger's (or the palm's) bone stops at its capsule. Bones whose
/// capsule has no such point get no term.
[[nodiscard]] std::vector<std::shared_ptr<Term>> bone_collider_terms(std::shared_ptr<const Flesh> flesh, double dhat,
                                                                     double stiffness);
/// The points each bone's capsule acts on (welded ids of contact_surface's points), per bone in flesh.bones'
/// order (empty for a bone without a radius or without such points).
[[nodiscard]] std::vector<std::vector<int>> bone_collider_points(const Flesh& flesh, double dhat);

/// The joints' world transforms at time t of the clip.
[[nodiscard]] std::vector<Eigen::Affine3d> joint_world(const Flesh& flesh, double t);
/// The index of the joint `name` in the model's skeleton. Throws RigError (one line: `where`, the model and
/// a few of its joints) when it has none of that name.
[[nodiscard]] int joint_named(const RiggedModel& model, const std::string& name, const std::string& where);
/// The render surface (model order, 3 by #v) embedded in the volume at positions x (3 #V).
[[nodiscard]] Eigen::Matrix3Xd flesh_surface(const Flesh& flesh, const Eigen::VectorXd& x);
/// The render surface's unit vertex normals at these positions (model order, 3 by #v): rig/normals.hpp.
[[nodiscard]] Eigen::Matrix3Xd surface_normals(const Flesh& flesh, const Eigen::Matrix3Xd& positions);
/// The render surface posed by linear blend skinning at time t (model order, 3 by #v).
[[nodiscard]] Eigen::Matrix3Xd skinned_surface(const Flesh& flesh, double t);
/// The volume enclosed by the render surface at these positions (model order).
[[nodiscard]] double surface_volume(const Flesh& flesh, const Eigen::Matrix3Xd& positions);

}  // namespace snh
