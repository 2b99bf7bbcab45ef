#include "snh/setup/flesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <stdexcept>

#include <Eigen/SVD>
#include <fmt/format.h>

#include "snh/embed/lattice.hpp"
#include "snh/embed/winding_number.hpp"
#include "snh/fem/attachment_term.hpp"
#include "snh/fem/collider_term.hpp"
#include "snh/fem/contact_term.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/rig/skinning.hpp"

namespace snh {
namespace {

/// The joint of this name, or RigError naming the model and a few of its joints.
int joint_named(const RiggedModel& model, const std::string& name, const std::string& where) {
  const int j = model.skeleton.find(name);
  if (j >= 0) return j;
  std::string known;
  for (int k = 0; k < model.skeleton.size() && k < 6; ++k) known += (k ? ", " : "") + model.skeleton.joints[k].name;
  if (model.skeleton.size() > 6) known += ", ...";
  throw RigError(fmt::format("{}: the model {} has no joint \"{}\" (its joints: {})", where, model.source.string(), name, known));
}

/// The binding without the vertices at a split grid node (one of several vertices there) whose cells' material
/// lies outside their bone's capsule: where two fingers share a cube, the copy of a node that belongs to the
/// other finger's piece is not carried by this finger's bone.
Binding keep_bound_material(const Binding& binding, const std::vector<Bone>& bones, const Lattice& lattice) {
  std::vector<std::vector<int>> cells_of(static_cast<std::size_t>(lattice.mesh.vertex_count()));
  for (Eigen::Index c = 0; c < lattice.mesh.cell_count(); ++c)
    for (int k = 0; k < 8; ++k)
      if (const int v = lattice.mesh.cells(k, c); lattice.copies[static_cast<std::size_t>(v)] > 1)
        cells_of[static_cast<std::size_t>(v)].push_back(static_cast<int>(c));
  Binding out;
  for (std::size_t i = 0; i < binding.vertex.size(); ++i) {
    const int v = binding.vertex[i];
    bool keep = lattice.copies[static_cast<std::size_t>(v)] <= 1;
    const Bone& bone = bones[static_cast<std::size_t>(binding.bone[i])];
    for (const int c : cells_of[static_cast<std::size_t>(v)]) {
      const Eigen::Matrix3Xd samples = lattice.cell_samples(c);
      for (Eigen::Index k = 0; k < samples.cols() && !keep; ++k)
        keep = segment_distance(bone.a, bone.b, samples.col(k)) <= bone.radius;
      if (keep) break;
    }
    if (keep) {
      out.vertex.push_back(v);
      out.bone.push_back(binding.bone[i]);
    }
  }
  return out;
}

/// Parts of the volume (cells joined through shared vertices) that no bone binds would float free: each is bound
/// whole to the bone of the joint its embedded skin is weighted to most (a prop or an eye that only its joint
/// carries). Returns one "N vertices to JOINT" entry per part so bound.
std::vector<std::string> bind_free_parts(Flesh& f) {
  const VolumeMesh& vol = f.volume;
  const auto n = static_cast<int>(vol.vertex_count());
  std::vector<int> parent(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) parent[static_cast<std::size_t>(i)] = i;
  const auto root = [&](int i) {
    while (parent[static_cast<std::size_t>(i)] != i) i = parent[static_cast<std::size_t>(i)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(i)])];
    return i;
  };
  for (Eigen::Index c = 0; c < vol.cell_count(); ++c)
    for (Eigen::Index k = 1; k < vol.cells.rows(); ++k) {
      const int a = root(vol.cells(0, c)), b = root(vol.cells(k, c));
      if (a != b) parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
    }
  std::vector<char> held(static_cast<std::size_t>(n), 0);
  for (const int v : f.binding.vertex) held[static_cast<std::size_t>(root(v))] = 1;
  const int joints = f.model.skeleton.size();
  std::map<int, std::vector<double>> weight;  // per free part's root: the skin's weight per joint
  for (Eigen::Index p = 0; p < f.embedding.vertex.cols(); ++p) {
    const int r = root(f.embedding.vertex(0, p));
    if (held[static_cast<std::size_t>(r)]) continue;
    std::vector<double>& w = weight[r];
    w.resize(static_cast<std::size_t>(joints), 0.0);
    for (int k = 0; k < 4; ++k) w[static_cast<std::size_t>(f.model.joint_index(k, p))] += f.model.joint_weight(k, p);
  }
  std::vector<std::string> out;
  std::map<int, std::pair<int, int>> bone_of;  // per free part's root: its bone and its vertex count
  for (const auto& [r, w] : weight) {
    const int joint = static_cast<int>(std::max_element(w.begin(), w.end()) - w.begin());
    for (std::size_t b = 0; b < f.bones.size(); ++b)
      if (f.bones[b].joint == joint) {
        bone_of[r] = {static_cast<int>(b), 0};
        break;
      }
  }
  std::vector<std::pair<int, int>> added;  // (vertex, bone)
  for (int v = 0; v < n; ++v)
    if (const auto it = bone_of.find(root(v)); it != bone_of.end()) {
      added.emplace_back(v, it->second.first);
      ++it->second.second;
    }
  for (const auto& [r, bone_count] : bone_of)
    out.push_back(fmt::format("{} vertices to {}", bone_count.second,
                              f.model.skeleton.joints[static_cast<std::size_t>(f.bones[static_cast<std::size_t>(bone_count.first)].joint)].name));
  if (added.empty()) return out;
  for (std::size_t i = 0; i < f.binding.vertex.size(); ++i) added.emplace_back(f.binding.vertex[i], f.binding.bone[i]);
  std::sort(added.begin(), added.end());
  f.binding.vertex.clear();
  f.binding.bone.clear();
  for (const auto& [v, b] : added) {
    f.binding.vertex.push_back(v);
    f.binding.bone.push_back(b);
  }
  return out;
}

Clip choose_clip(const FleshSpec& spec, const RiggedModel& model, const std::string& where) {
  if (!spec.animation.empty() && !spec.keyframes.empty())
    throw std::invalid_argument(fmt::format("{}: give an animation clip or keyframes, not both", where));
  if (!spec.animation.empty()) return find_clip(model, spec.animation);
  if (!spec.keyframes.empty()) {
    std::vector<JointKeys> keys;
    for (const KeyframeSpec& k : spec.keyframes)
      for (const std::string& name : k.joints)
        keys.push_back({.joint = joint_named(model, name, where), .times = k.times, .rotations = k.rotations});
    for (std::size_t a = 0; a < keys.size(); ++a)
      for (std::size_t b = a + 1; b < keys.size(); ++b)
        if (keys[a].joint == keys[b].joint)
          throw std::invalid_argument(fmt::format("{}: joint \"{}\" is keyframed twice", where,
                                                  model.skeleton.joints[keys[a].joint].name));
    return clip_from_keys("keyframes", model.skeleton, keys);
  }
  if (const int c = default_clip(model); c >= 0) return model.clips[static_cast<std::size_t>(c)];
  throw RigError(fmt::format("{}: the model {} has no animation clip: give keyframes (a scene's flesh.keyframes)", where,
                             model.source.string()));
}

/// Vertices carried rigidly by their bones' joints: their rest positions in the joints' rest frames, and
/// the joints' current frames of them.
class BoneCarried {
 public:
  BoneCarried(std::shared_ptr<const Flesh> flesh, const Binding& binding) : flesh_(std::move(flesh)) {
    joint_.resize(binding.vertex.size());
    local_.resize(3, static_cast<Eigen::Index>(binding.vertex.size()));
    for (std::size_t i = 0; i < binding.vertex.size(); ++i) {
      const int j = flesh_->bones[binding.bone[i]].joint;
      joint_[i] = j;
      local_.col(static_cast<Eigen::Index>(i)) = flesh_->bind_world[j].inverse() * flesh_->volume.vertices.col(binding.vertex[i]);
    }
  }
  void at(double t, Eigen::Matrix3Xd& out) const {
    const std::vector<Eigen::Affine3d> world = joint_world(*flesh_, t);
    out.resize(3, local_.cols());
    for (Eigen::Index i = 0; i < local_.cols(); ++i) out.col(i) = world[joint_[i]] * local_.col(i);
  }

 private:
  std::shared_ptr<const Flesh> flesh_;
  std::vector<int> joint_;
  Eigen::Matrix3Xd local_;
};

/// The hard-bound vertices' targets.
class BoneMotion final : public KinematicProvider {
 public:
  explicit BoneMotion(const std::shared_ptr<const Flesh>& flesh) : carried_(flesh, flesh->binding) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override { carried_.at(t, out); }

 private:
  BoneCarried carried_;
};

}  // namespace

int flesh_resolution(const std::vector<Bone>& bones, const BoneReach& reach, const Eigen::Matrix3Xd& surface, double surface_volume,
                     std::string& reason) {
  constexpr int kLeast = 16, kMost = 1000;
  constexpr double kMostCells = 2e4;
  const double longest = (surface.rowwise().maxCoeff() - surface.rowwise().minCoeff()).maxCoeff();
  // The thinnest capsule among the bones nearest to some skin vertex.
  int thinnest = -1;
  for (std::size_t b = 0; b < bones.size(); ++b)
    if (reach.closest_of[b] > 0 && bones[b].radius > 0.0 && (thinnest < 0 || bones[b].radius < bones[static_cast<std::size_t>(thinnest)].radius))
      thinnest = static_cast<int>(b);
  int n = kLeast;
  reason = fmt::format("the default {}", kLeast);
  if (thinnest >= 0) {
    const Bone& t = bones[static_cast<std::size_t>(thinnest)];
    const double wanted = std::ceil(longest / (2.0 / std::sqrt(3.0) * t.radius));
    if (wanted > kLeast) {
      n = static_cast<int>(std::min<double>(wanted, kMost));
      reason = fmt::format("chosen: cells no wider than 2/sqrt(3) of the thinnest capsule, {} of radius {:.4g}, so that every "
                           "bone binds flesh",
                           t.name, t.radius);
    }
  }
  // Cells kept about twice the skin's volume over h³ (a coarse lattice holds 1.5 to 3.5 times it): capped.
  const double most = std::floor(longest / std::cbrt(2.0 * surface_volume / kMostCells));
  if (n > kLeast && n > most) {
    n = std::max(kLeast, static_cast<int>(most));
    reason += fmt::format(", capped at about {:.0f} cells", kMostCells);
  }
  return n;
}

Flesh build_flesh(const FleshSpec& spec, const std::string& where) {
  Flesh f;
  f.model = read_model(spec.model);
  f.bind = place_at_bind_pose(f.model);
  const RiggedModel& m = f.model;
  // Skins as characters have them: holes (a mouth, a neck), several meshes, either orientation. The lattice
  // takes them all (its inside test is the generalized winding number); TetGen needs a closed surface.
  f.edges = edge_counts(m.surface_triangles);
  f.normal_groups = normal_groups(m);
  if (spec.volume == FleshVolume::tets && (f.edges.open > 0 || f.edges.non_manifold > 0))
    throw RigError(fmt::format("{}: the surface (welded by position) is not closed: {} open and {} non-manifold edges of {}; "
                               "tets (TetGen) need a closed surface: use the lattice (--volume lattice), which takes open skins",
                               m.source.string(), f.edges.open, f.edges.non_manifold, f.edges.edges));
  f.clip = choose_clip(spec, m, where);
  f.bind_world = f.bind.joints;
  const double signed_volume = enclosed_volume(m.surface_vertices, m.surface_triangles);
  f.inside_out = signed_volume < 0.0;
  f.surface_volume = std::abs(signed_volume);
  if (!(f.surface_volume > 0.0))
    throw RigError(fmt::format("{}: the surface encloses no volume ({:g}): is it flat?", m.source.string(), signed_volume));

  f.bones = bones_of(m.skeleton, f.bind_world);
  const BoneReach reach = bone_reach(f.bones, m.surface_vertices);
  const std::vector<double> radii = default_radii(reach);
  for (std::size_t b = 0; b < f.bones.size(); ++b) f.bones[b].radius = radii[b];
  const double longest = (m.surface_vertices.rowwise().maxCoeff() - m.surface_vertices.rowwise().minCoeff()).maxCoeff();
  if (spec.cell_size > 0.0 && spec.resolution > 0)
    throw std::invalid_argument(fmt::format("{}: give a resolution or a cell size, not both", where));
  if (spec.cell_size > 0.0) {
    const double n = std::ceil(longest / spec.cell_size * (1.0 - 1e-12));
    if (!(n <= 1000))
      throw std::invalid_argument(fmt::format("{}: cell size {:g} makes {:.3g} cells along the model's longest side ({:g}); at most 1000",
                                              where, spec.cell_size, n, longest));
    f.resolution = std::max(1, static_cast<int>(n));
    f.resolution_reason = fmt::format("from the cell size {:g}", spec.cell_size);
  } else if (spec.resolution > 0) {
    f.resolution = spec.resolution;
    f.resolution_reason = "given";
  } else {
    f.resolution = flesh_resolution(f.bones, reach, m.surface_vertices, f.surface_volume, f.resolution_reason);
  }

  std::unique_ptr<Lattice> split_lattice;  // the lattice, where a cube is split into pieces
  if (spec.volume == FleshVolume::lattice) {
    const Lattice lattice = lattice_for_surface(m.surface_vertices, m.surface_triangles, f.resolution,
                                                 spec.split_cells ? 4 : 0);
    f.volume = lattice.mesh;
    f.cell_size = lattice.spacing;
    f.volume_of_cells = static_cast<double>(f.volume.cell_count()) * std::pow(lattice.spacing, 3);
    f.embedding = embed_surface_in_lattice(lattice, m.surface_vertices, m.surface_triangles, m.vertices, m.weld);
    f.split_cubes = lattice.split_cubes;
    f.copied_vertices = 0;
    for (const int c : lattice.copies) f.copied_vertices += c > 1 ? 1 : 0;
    split_lattice = f.copied_vertices > 0 ? std::make_unique<Lattice>(lattice) : nullptr;
  } else {
    f.cell_size = longest / f.resolution;
    // No tet larger than a sixth of a cube of the lattice's size (the five or six tets a cube splits into).
    MeshFile tets = tetrahedralize(SurfaceMesh{m.surface_vertices, m.surface_triangles}, spec.model,
                                   std::pow(f.cell_size, 3) / 6.0);
    f.volume = std::move(tets.mesh);
    f.volume_of_cells = mesh_volume(f.volume);
    f.embedding = embed_in_tets(f.volume, m.vertices);
  }

  std::vector<bool> radius_given(f.bones.size(), false);
  for (const BoneRadius& r : spec.radii) {
    const int j = joint_named(m, r.joint, where);
    if (!(r.radius > 0.0) || !std::isfinite(r.radius))
      throw std::invalid_argument(fmt::format("{}: bone radius of \"{}\" must be a positive number, got {:g}", where, r.joint, r.radius));
    for (std::size_t b = 0; b < f.bones.size(); ++b)
      if (f.bones[b].joint == j) f.bones[b].radius = r.radius, radius_given[b] = true;
  }
  f.binding = bind_to_bones(f.bones, f.volume.vertices);
  if (split_lattice) f.binding = keep_bound_material(f.binding, f.bones, *split_lattice);
  if (!f.binding.vertex.empty()) f.free_parts = bind_free_parts(f);
  f.bound_per_bone = f.binding.count_per_bone(static_cast<int>(f.bones.size()));
  for (std::size_t b = 0; b < f.bones.size(); ++b)
    if (radius_given[b] && f.bound_per_bone[b] == 0)
      throw std::invalid_argument(fmt::format("{}: bone {} binds no volume vertex with the radius {:g} given for it (cells are "
                                              "{:.3g} wide: raise the radius or the resolution)",
                                              where, f.bones[b].name, f.bones[b].radius, f.cell_size));
  if (f.binding.vertex.empty())
    throw std::invalid_argument(fmt::format("{}: no volume vertex lies inside a bone's capsule (cells are {:.3g} wide): raise the "
                                            "resolution or set bone radii",
                                            where, f.cell_size));
  if (spec.soft_shell > 0.0) f.soft = soft_bind_to_bones(f.bones, f.volume.vertices, spec.soft_shell, f.binding);
  if (spec.joint_cells != JointCells::hard) {
    JointSplit split = split_at_joints(f.binding, f.bones, f.volume.cells, f.volume.vertex_count());
    f.binding = std::move(split.kept);
    f.released = std::move(split.released);
    if (spec.joint_cells == JointCells::soft) f.soft = merge_soft(f.soft, f.released, 1.0);
    f.bound_per_bone = f.binding.count_per_bone(static_cast<int>(f.bones.size()));
    if (f.binding.vertex.empty() && f.soft.vertex.empty())
      throw std::invalid_argument(fmt::format("{}: every bound vertex lies in a cell spanning a joint, and joint cells are free: "
                                              "nothing holds the flesh (raise the resolution, or bind joint cells soft or hard)",
                                              where));
  }
  return f;
}

KinematicSet bone_kinematics(std::shared_ptr<const Flesh> flesh) {
  KinematicSet set;
  set.name = "bones";
  set.vertices = flesh->binding.vertex;
  set.provider = std::make_shared<BoneMotion>(flesh);
  return set;
}

std::shared_ptr<Term> soft_binding_term(std::shared_ptr<const Flesh> flesh, double soft_stiffness, double youngs) {
  const SoftBinding& soft = flesh->soft;
  if (soft.vertex.empty()) return nullptr;
  const double k = soft_stiffness * youngs * flesh->cell_size;
  const Eigen::VectorXd stiffness = k * Eigen::Map<const Eigen::VectorXd>(soft.weight.data(), static_cast<Eigen::Index>(soft.weight.size()));
  auto carried = std::make_shared<BoneCarried>(flesh, soft);
  return std::make_shared<AttachmentTerm>(soft.vertex, stiffness,
                                          [carried](double t, Eigen::Matrix3Xd& out) { carried->at(t, out); });
}

std::function<void(double, std::vector<Eigen::Matrix<double, 3, 4>>&)> flesh_carrier(std::shared_ptr<const Flesh> flesh) {
  // Each volume vertex takes the joints and weights of its nearest model vertex (at rest).
  const Eigen::Matrix3Xd& X = flesh->volume.vertices;
  const Eigen::Matrix3Xd& S = flesh->model.vertices;
  const Eigen::Index n = X.cols();
  auto joints = std::make_shared<Eigen::Matrix4Xi>(4, n);
  auto weights = std::make_shared<Eigen::Matrix4Xd>(4, n);
#pragma omp parallel for schedule(static)
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Index nearest = 0;
    (S.colwise() - X.col(v)).colwise().squaredNorm().minCoeff(&nearest);
    joints->col(v) = flesh->model.joint_index.col(nearest);
    weights->col(v) = flesh->model.joint_weight.col(nearest);
  }
  return [flesh, joints, weights](double t, std::vector<Eigen::Matrix<double, 3, 4>>& frames) {
    const std::vector<Eigen::Affine3d> world = joint_world(*flesh, t);
    std::vector<Eigen::Matrix<double, 3, 4>> motion(world.size());
    for (std::size_t j = 0; j < world.size(); ++j) motion[j] = (world[j] * flesh->bind_world[j].inverse()).matrix().topRows<3>();
    const Eigen::Index n = joints->cols();
    frames.assign(static_cast<std::size_t>(n), Eigen::Matrix<double, 3, 4>::Zero());
    for (Eigen::Index v = 0; v < n; ++v)
      for (int k = 0; k < 4; ++k)
        if (const double w = (*weights)(k, v); w != 0.0) frames[static_cast<std::size_t>(v)] += w * motion[static_cast<std::size_t>((*joints)(k, v))];
  };
}

std::vector<std::vector<int>> bone_collider_points(const Flesh& flesh, double dhat) {
  const RiggedModel& m = flesh.model;
  const EmbeddedSurface skin = contact_surface(flesh);
  const Eigen::Matrix3Xd rest = skin.points.apply(flesh.volume.vertices);
  const auto n = static_cast<Eigen::Index>(rest.cols());
  // Each welded point's skin weights: those of its first model vertex (as contact_surface embeds it).
  std::vector<int> model_vertex(static_cast<std::size_t>(n), -1);
  for (std::size_t v = 0; v < m.weld.size(); ++v)
    if (int& first = model_vertex[static_cast<std::size_t>(m.weld[v])]; first < 0) first = static_cast<int>(v);
  const auto skinned_to = [&](Eigen::Index i, int joint) {
    const auto v = static_cast<Eigen::Index>(model_vertex[static_cast<std::size_t>(i)]);
    for (int k = 0; k < 4; ++k)
      if (joint >= 0 && m.joint_index(k, v) == joint && m.joint_weight(k, v) > 0.0) return true;
    return false;
  };
  // The bone each volume vertex hangs on: hard-bound, or released at a joint (then soft or free); −1: none.
  std::vector<int> bone_of(static_cast<std::size_t>(flesh.volume.vertex_count()), -1);
  std::vector<char> hard(bone_of.size(), 0);
  for (const Binding* b : {&flesh.released, &flesh.binding})
    for (std::size_t i = 0; i < b->vertex.size(); ++i) bone_of[static_cast<std::size_t>(b->vertex[i])] = b->bone[i];
  for (const int v : flesh.binding.vertex) hard[static_cast<std::size_t>(v)] = 1;
  const Eigen::MatrixXi& cell = skin.points.vertex;
  const double margin = 2.0 * dhat;
  std::vector<std::vector<int>> out(flesh.bones.size());
  for (std::size_t b = 0; b < flesh.bones.size(); ++b) {
    const Bone& bone = flesh.bones[b];
    if (!(bone.radius > 0.0)) continue;
    const int parent = m.skeleton.joints[static_cast<std::size_t>(bone.joint)].parent;
    for (Eigen::Index i = 0; i < n; ++i) {
      // Flesh that bends around the capsule's ends: skinned to its joint, the joint's parent or its child.
      if (skinned_to(i, bone.joint) || skinned_to(i, parent) || skinned_to(i, bone.child)) continue;
      // Flesh that hangs on the bone (a vertex of its cell bound to it), or that nothing can move (its cell
      // all bound: bones carry it, the barrier could not hold it off).
      bool on_bone = false, all_hard = true;
      for (Eigen::Index k = 0; k < cell.rows(); ++k) {
        on_bone = on_bone || bone_of[static_cast<std::size_t>(cell(k, i))] == static_cast<int>(b);
        all_hard = all_hard && hard[static_cast<std::size_t>(cell(k, i))];
      }
      if (on_bone || all_hard) continue;
      // Out of range at rest, with room: the rest state stays the first frame's solution.
      if (segment_distance(bone.a, bone.b, rest.col(i)) - bone.radius > margin) out[b].push_back(static_cast<int>(i));
    }
  }
  return out;
}

std::vector<std::shared_ptr<Term>> bone_collider_terms(std::shared_ptr<const Flesh> flesh, double dhat, double stiffness) {
  const EmbeddedSurface skin = contact_surface(*flesh);
  const std::vector<std::vector<int>> colliding = bone_collider_points(*flesh, dhat);
  std::vector<std::shared_ptr<Term>> terms;
  for (std::size_t b = 0; b < flesh->bones.size(); ++b) {
    const Bone& bone = flesh->bones[b];
    const std::vector<int>& points = colliding[b];
    if (points.empty()) continue;
    ColliderShape shape;
    shape.kind = bone.a == bone.b ? ColliderShape::Kind::sphere : ColliderShape::Kind::capsule;
    shape.a = bone.a;
    shape.b = bone.b;
    shape.radius = bone.radius;
    const Eigen::Affine3d rest_inverse = flesh->bind_world[static_cast<std::size_t>(bone.joint)].inverse();
    // The joint's motion from rest is rigid up to the rounding of the file's single-precision transforms:
    // taken as the nearest rotation (polar decomposition) and the mean scale, as the shape needs.
    ColliderPose pose = [flesh, joint = bone.joint, rest_inverse](double t) {
      Eigen::Affine3d a = joint_world(*flesh, t)[static_cast<std::size_t>(joint)] * rest_inverse;
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a.linear(), Eigen::ComputeFullU | Eigen::ComputeFullV);
      Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
      a.linear() = svd.singularValues().mean() * r;
      return a;
    };
    terms.push_back(std::make_shared<ShapeColliderTerm>(
        EmbeddedPoints(skin.points.vertex(Eigen::all, points), skin.points.weight(Eigen::all, points), "collider: bone", -1), shape,
        std::move(pose), dhat, stiffness));
  }
  return terms;
}

std::vector<Eigen::Affine3d> joint_world(const Flesh& flesh, double t) {
  return flesh.model.skeleton.world(sample(flesh.clip, flesh.model.skeleton, t));
}

Eigen::Matrix3Xd flesh_surface(const Flesh& flesh, const Eigen::VectorXd& x) { return flesh.embedding.apply(x); }

Eigen::Matrix3Xd surface_normals(const Flesh& flesh, const Eigen::Matrix3Xd& positions) {
  return vertex_normals(flesh.model, flesh.normal_groups, positions);
}

Eigen::Matrix3Xd skinned_surface(const Flesh& flesh, double t) { return skin_vertices(flesh.model, joint_world(flesh, t)); }

EmbeddedSurface contact_surface(const Flesh& flesh) {
  const RiggedModel& m = flesh.model;
  EmbeddedSurface s;
  s.triangles = m.surface_triangles;
  const auto welded = static_cast<Eigen::Index>(m.surface_vertices.cols());
  Embedding& p = s.points;
  p.cell.resize(static_cast<std::size_t>(welded));
  p.vertex.resize(flesh.embedding.vertex.rows(), welded);
  p.weight.resize(flesh.embedding.weight.rows(), welded);
  std::vector<bool> seen(static_cast<std::size_t>(welded), false);
  for (std::size_t v = 0; v < m.weld.size(); ++v) {
    const int w = m.weld[v];
    if (seen[static_cast<std::size_t>(w)]) continue;
    seen[static_cast<std::size_t>(w)] = true;
    p.cell[static_cast<std::size_t>(w)] = flesh.embedding.cell[v];
    p.vertex.col(w) = flesh.embedding.vertex.col(static_cast<Eigen::Index>(v));
    p.weight.col(w) = flesh.embedding.weight.col(static_cast<Eigen::Index>(v));
  }
  return s;
}

double flesh_contact_dhat(const Flesh& flesh) {
  const Eigen::Matrix3Xd& X = flesh.model.surface_vertices;
  const Eigen::Matrix3Xi& F = flesh.model.surface_triangles;
  double sum = 0.0;
  for (Eigen::Index t = 0; t < F.cols(); ++t)
    for (int k = 0; k < 3; ++k) sum += (X.col(F(k, t)) - X.col(F((k + 1) % 3, t))).norm();
  const double quarter = F.cols() > 0 ? 0.25 * sum / (3.0 * static_cast<double>(F.cols())) : 0.1 * flesh.cell_size;
  // At most half the surface's smallest distance at rest (pairs that share no vertex), so that nothing is in
  // contact at the start: fingers lying close together at rest are not pushed apart by the barrier.
  const EmbeddedSurface surface = contact_surface(flesh);
  const VolumeMesh& volume = flesh.volume;
  const ContactTerm probe(surface.triangles,
                          EmbeddedPoints(surface.points.vertex, surface.points.weight, "contact: render surface", volume.vertex_count()),
                          volume.vertices, quarter, 1.0);
  const double closest = probe.min_distance(Eigen::Map<const Eigen::VectorXd>(volume.vertices.data(), volume.vertices.size()));
  return closest > 0.0 ? std::min(quarter, 0.5 * closest) : quarter;
}

double flesh_contact_stiffness(const Flesh& flesh, double youngs, double dhat) { return youngs * flesh.cell_size / (dhat * dhat); }

double surface_volume(const Flesh& flesh, const Eigen::Matrix3Xd& positions) {
  return enclosed_volume(positions, flesh.model.triangles);
}

}  // namespace snh
