#include "snh/setup/flesh.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
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
#include "snh/math/union_find.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/rig/skinning.hpp"
#include "snh/solve/linear_solver.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace snh {

int joint_named(const RiggedModel& model, const std::string& name, const std::string& where) {
  const int j = model.skeleton.find(name);
  if (j >= 0) return j;
  std::string known;
  for (int k = 0; k < model.skeleton.size() && k < 6; ++k) known += (k ? ", " : "") + model.skeleton.joints[k].name;
  if (model.skeleton.size() > 6) known += ", ...";
  throw RigError(fmt::format("{}: the model {} has no joint \"{}\" (its joints: {})", where, model.source.string(), name, known));
}

namespace {

/// A lattice per solid on one grid, their cells one after another in the volume.
struct SolidLattices {
  std::vector<Lattice> lattice;             ///< per solid
  std::vector<std::vector<int>> vertex_of;  ///< per solid: the volume vertex of each of its lattice's vertices
};

/// The binding without the vertices at a split grid node (one of several vertices there) whose cells' material
/// lies outside their bone's capsule: where two fingers share a cube, the copy of a node that belongs to the
/// other finger's piece is not carried by this finger's bone.
Binding keep_bound_material(const Binding& binding, const std::vector<Bone>& bones, const SolidLattices& lattices,
                            Eigen::Index volume_vertices) {
  std::vector<std::vector<std::pair<int, int>>> cells_of(static_cast<std::size_t>(volume_vertices));  // (solid, cell)
  for (std::size_t s = 0; s < lattices.lattice.size(); ++s) {
    const Lattice& L = lattices.lattice[s];
    for (Eigen::Index c = 0; c < L.mesh.cell_count(); ++c)
      for (int k = 0; k < 8; ++k)
        if (const int v = L.mesh.cells(k, c); L.copies[static_cast<std::size_t>(v)] > 1)
          cells_of[static_cast<std::size_t>(lattices.vertex_of[s][static_cast<std::size_t>(v)])].emplace_back(static_cast<int>(s),
                                                                                                            static_cast<int>(c));
  }
  Binding out;
  for (std::size_t i = 0; i < binding.vertex.size(); ++i) {
    const auto& cells = cells_of[static_cast<std::size_t>(binding.vertex[i])];
    bool keep = cells.empty();
    const Bone& bone = bones[static_cast<std::size_t>(binding.bone[i])];
    for (const auto& [solid, c] : cells) {
      const Eigen::Matrix3Xd samples = lattices.lattice[static_cast<std::size_t>(solid)].cell_samples(c);
      for (Eigen::Index k = 0; k < samples.cols() && !keep; ++k)
        keep = segment_distance(bone.a, bone.b, samples.col(k)) <= bone.radius;
      if (keep) break;
    }
    if (keep) {
      out.vertex.push_back(binding.vertex[i]);
      out.bone.push_back(binding.bone[i]);
    }
  }
  return out;
}

/// Per model vertex whether a triangle uses it (meshes that share a vertex buffer list each other's vertices).
std::vector<char> used_vertices(const RiggedModel& m) {
  std::vector<char> used(static_cast<std::size_t>(m.vertices.cols()), 0);
  for (Eigen::Index t = 0; t < m.triangles.cols(); ++t)
    for (int c = 0; c < 3; ++c) used[static_cast<std::size_t>(m.triangles(c, t))] = 1;
  return used;
}

/// The solid of each of the model's meshes (parts): meshes whose skins share a joint (a weight above zero) are
/// one solid; the others are kept apart even where they overlap at rest, and glued only where they share skin
/// vertices (build_solid_lattices).
///   used  used_vertices(m)
std::vector<int> solids_of_parts(const RiggedModel& m, const std::vector<char>& used) {
  const std::size_t parts = m.parts.size();
  UnionFind groups(parts);
  std::vector<int> part_of_joint(static_cast<std::size_t>(m.skeleton.size()), -1);
  for (std::size_t p = 0; p < parts; ++p)
    for (Eigen::Index v = m.parts[p].first_vertex; v < m.parts[p].first_vertex + m.parts[p].vertices; ++v)
      for (int k = 0; k < 4 && used[static_cast<std::size_t>(v)]; ++k)
        if (m.joint_weight(k, v) > 0.0) {
          int& first = part_of_joint[static_cast<std::size_t>(m.joint_index(k, v))];
          if (first < 0) first = static_cast<int>(p);
          groups.join(first, static_cast<int>(p));
        }
  std::vector<int> solid(parts, -1), number(parts, -1);
  int solids = 0;
  for (std::size_t p = 0; p < parts; ++p) {
    int& n = number[static_cast<std::size_t>(groups.root(static_cast<int>(p)))];
    if (n < 0) n = solids++;
    solid[p] = n;
  }
  return solid;
}

/// Seams between solids: at a skin vertex (welded) of several solids, the corners of its model vertices' cells
/// that sit at one grid node become one vertex. Returns each vertex's number after (vertices of the lattices one
/// solid after another before), `kept` the count after, and `seams` the skin vertices glued.
std::vector<int> glue_seams(const RiggedModel& m, const std::vector<Lattice>& lattices, const std::vector<int>& solid_of_vertex,
                            const std::vector<std::vector<int>>& solids_of_weld, const Embedding& e, int& kept, int& seams) {
  const auto vertices = static_cast<Eigen::Index>(solid_of_vertex.size());
  UnionFind groups(static_cast<std::size_t>(vertices));
  std::vector<Eigen::Index> first_of_solid;
  {
    Eigen::Index n = 0;
    for (const Lattice& L : lattices) first_of_solid.push_back(n), n += L.mesh.vertex_count();
  }
  const auto node_of = [&](int v) {  // the grid node of a volume vertex (before gluing)
    const int s = solid_of_vertex[static_cast<std::size_t>(v)];
    const Lattice& L = lattices[static_cast<std::size_t>(s)];
    const Eigen::Vector3d g = L.grid_coordinates(L.mesh.vertices.col(v - first_of_solid[static_cast<std::size_t>(s)]));
    return std::array<long, 3>{std::lround(g.x()), std::lround(g.y()), std::lround(g.z())};
  };
  std::vector<std::vector<Eigen::Index>> points_of_weld(static_cast<std::size_t>(m.surface_vertices.cols()));
  for (Eigen::Index v = 0; v < m.vertices.cols(); ++v)
    if (solids_of_weld[static_cast<std::size_t>(m.weld[static_cast<std::size_t>(v)])].size() > 1)
      points_of_weld[static_cast<std::size_t>(m.weld[static_cast<std::size_t>(v)])].push_back(v);
  seams = 0;
  for (const std::vector<Eigen::Index>& at : points_of_weld) {
    if (at.empty()) continue;
    ++seams;
    std::map<std::array<long, 3>, int> first_at_node;
    for (const Eigen::Index p : at)
      for (int k = 0; k < 8; ++k) {
        const int v = e.vertex(k, p);
        const auto [it, fresh] = first_at_node.emplace(node_of(v), v);
        if (fresh) continue;
        groups.join(it->second, v);
      }
  }
  std::vector<int> renumber(static_cast<std::size_t>(vertices), -1);
  kept = 0;
  for (Eigen::Index v = 0; v < vertices; ++v)
    if (groups.root(static_cast<int>(v)) == v) renumber[static_cast<std::size_t>(v)] = kept++;
  for (Eigen::Index v = 0; v < vertices; ++v) renumber[static_cast<std::size_t>(v)] = renumber[static_cast<std::size_t>(groups.root(static_cast<int>(v)))];
  return renumber;
}

/// The flesh's volume, embedding and solids from a lattice per solid (solid_of_part: one per mesh) on one grid.
/// Where two solids share a skin vertex (a seam welded by position), the grid nodes of the cells embedding it
/// are one vertex for both, so the solids are glued along their seams and nowhere else.
///   used  used_vertices(f.model)
SolidLattices build_solid_lattices(Flesh& f, const std::vector<int>& solid_of_part, const std::vector<char>& used, int samples) {
  const RiggedModel& m = f.model;
  const int solids = solid_of_part.empty() ? 0 : *std::max_element(solid_of_part.begin(), solid_of_part.end()) + 1;
  std::vector<int> solid_of_point(static_cast<std::size_t>(m.vertices.cols()), -1);
  std::vector<std::vector<int>> solids_of_weld(static_cast<std::size_t>(m.surface_vertices.cols()));
  f.solids.assign(static_cast<std::size_t>(solids), std::string());
  // A vertex its mesh's triangles use is its mesh's solid's; one they do not use (meshes sharing a vertex
  // buffer list each other's vertices) goes with the solid of a used vertex at its place, if any.
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t p = 0; p < m.parts.size(); ++p) {
      const int s = solid_of_part[p];
      if (pass == 0) {
        std::string& name = f.solids[static_cast<std::size_t>(s)];
        name += (name.empty() ? "" : " + ") + m.parts[p].name;
      }
      for (Eigen::Index v = m.parts[p].first_vertex; v < m.parts[p].first_vertex + m.parts[p].vertices; ++v) {
        if ((pass == 0) != (used[static_cast<std::size_t>(v)] != 0)) continue;
        std::vector<int>& at = solids_of_weld[static_cast<std::size_t>(m.weld[static_cast<std::size_t>(v)])];
        solid_of_point[static_cast<std::size_t>(v)] = pass == 1 && !at.empty() ? at.front() : s;
        if (at.empty() || (pass == 0 && std::find(at.begin(), at.end(), s) == at.end())) at.push_back(s);
      }
    }
  f.solid_of_point = solid_of_point;
  for (const int s : solid_of_point)
    if (s < 0) throw std::logic_error("build_flesh: a model vertex in no mesh");
  const Lattice grid = lattice_grid(m.surface_vertices, m.surface_triangles, f.resolution);
  SolidLattices out;
  // Each solid's lattice, its vertices numbered one solid after another (before the seams are glued).
  Embedding e;
  e.cell.assign(static_cast<std::size_t>(m.vertices.cols()), -1);
  e.vertex.resize(8, m.vertices.cols());
  e.weight.resize(8, m.vertices.cols());
  f.split_cubes = 0;
  f.copied_vertices = 0;
  Eigen::Index vertices = 0, cells = 0;
  std::vector<int> solid_of_vertex;
  for (int s = 0; s < solids; ++s) {
    std::vector<Eigen::Index> triangles, points;
    for (Eigen::Index t = 0; t < m.surface_triangles.cols(); ++t) {
      bool in = true;  // a triangle is the solid's when all its corners are (a seam's triangles: both solids')
      for (int c = 0; c < 3 && in; ++c) {
        const std::vector<int>& at = solids_of_weld[static_cast<std::size_t>(m.surface_triangles(c, t))];
        in = std::find(at.begin(), at.end(), s) != at.end();
      }
      if (in) triangles.push_back(t);
    }
    for (Eigen::Index v = 0; v < m.vertices.cols(); ++v)
      if (solid_of_point[static_cast<std::size_t>(v)] == s) points.push_back(v);
    if (triangles.empty())
      throw RigError(fmt::format("{}: the meshes {} keep no triangle once welded by position", m.source.string(),
                                 f.solids[static_cast<std::size_t>(s)]));
    const Eigen::Matrix3Xi F = m.surface_triangles(Eigen::all, triangles);
    Lattice L = lattice_on_grid(grid, m.surface_vertices, F, samples);
    std::vector<int> weld(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) weld[i] = m.weld[static_cast<std::size_t>(points[i])];
    const Embedding here = embed_surface_in_lattice(L, m.surface_vertices, F, m.vertices(Eigen::all, points), weld);
    for (std::size_t i = 0; i < points.size(); ++i) {
      e.cell[static_cast<std::size_t>(points[i])] = here.cell[i] + static_cast<int>(cells);
      e.vertex.col(points[i]) = here.vertex.col(static_cast<Eigen::Index>(i)).array() + static_cast<int>(vertices);
      e.weight.col(points[i]) = here.weight.col(static_cast<Eigen::Index>(i));
    }
    f.split_cubes += L.split_cubes;
    for (const int c : L.copies) f.copied_vertices += c > 1 ? 1 : 0;
    // The skin embedded, the index over the whole grid is not needed (keep_bound_material asks only
    // cell_samples): dropped, so that many solids do not hold a grid-sized array each.
    std::vector<int>().swap(L.cell_at);
    solid_of_vertex.insert(solid_of_vertex.end(), static_cast<std::size_t>(L.mesh.vertex_count()), s);
    vertices += L.mesh.vertex_count();
    cells += L.mesh.cell_count();
    out.lattice.push_back(std::move(L));
  }
  int kept = 0;
  const std::vector<int> renumber = glue_seams(m, out.lattice, solid_of_vertex, solids_of_weld, e, kept, f.seam_vertices);
  f.volume.type = CellType::hex8;
  f.volume.vertices.resize(3, kept);
  f.volume.cells.resize(8, cells);
  f.solid_of_volume_vertex.assign(static_cast<std::size_t>(kept), -1);
  Eigen::Index cell = 0, first = 0;
  for (std::size_t s = 0; s < out.lattice.size(); ++s) {
    const Lattice& L = out.lattice[s];
    std::vector<int>& of = out.vertex_of.emplace_back(static_cast<std::size_t>(L.mesh.vertex_count()));
    for (Eigen::Index v = 0; v < L.mesh.vertex_count(); ++v) {
      const int g = renumber[static_cast<std::size_t>(first + v)];
      of[static_cast<std::size_t>(v)] = g;
      f.volume.vertices.col(g) = L.mesh.vertices.col(v);
      if (f.solid_of_volume_vertex[static_cast<std::size_t>(g)] < 0) f.solid_of_volume_vertex[static_cast<std::size_t>(g)] = static_cast<int>(s);
    }
    for (Eigen::Index c = 0; c < L.mesh.cell_count(); ++c, ++cell)
      for (int k = 0; k < 8; ++k) f.volume.cells(k, cell) = of[static_cast<std::size_t>(L.mesh.cells(k, c))];
    first += L.mesh.vertex_count();
  }
  for (Eigen::Index p = 0; p < e.vertex.cols(); ++p)
    for (int k = 0; k < 8; ++k) e.vertex(k, p) = renumber[static_cast<std::size_t>(e.vertex(k, p))];
  f.embedding = std::move(e);
  f.cell_size = grid.spacing;
  f.volume_of_cells = static_cast<double>(f.volume.cell_count()) * std::pow(grid.spacing, 3);
  if (solids <= 1) f.solid_of_volume_vertex.clear();
  return out;
}

/// Parts of the volume (cells joined through shared vertices) that no bone binds would float free: each is bound
/// whole to the bone of the joint its embedded skin is weighted to most (a prop or an eye that only its joint
/// carries). Returns one "N vertices to JOINT" entry per part so bound.
std::vector<std::string> bind_free_parts(Flesh& f) {
  const VolumeMesh& vol = f.volume;
  const auto n = static_cast<int>(vol.vertex_count());
  UnionFind groups(static_cast<std::size_t>(n));
  const auto root = [&](int i) { return groups.root(i); };
  for (Eigen::Index c = 0; c < vol.cell_count(); ++c)
    for (Eigen::Index k = 1; k < vol.cells.rows(); ++k) {
      groups.join(vol.cells(0, c), vol.cells(k, c));
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

Flesh build_flesh(const FleshSpec& spec, const std::string& where, std::string_view solver) {
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
  for (std::size_t b = 0; b < f.bones.size(); ++b) f.bones[b].radius = spec.radius_scale * radii[b];
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

  SolidLattices lattices;  // the lattice of each solid, where a cube is split into pieces
  if (spec.volume == FleshVolume::lattice) {
    // A lattice too large to run is refused before it is built (at resolution 300, the limb's lattice took
    // 30 s and 3.6 GiB before the run's own check refused it; at 1000 it grew past 6 GiB): its cells fill at
    // least the skin's volume, a vertex per cell, so this estimate is below what the run's check will find.
    const double h = longest / f.resolution, cells = std::floor(f.surface_volume / (h * h * h));
    const ProblemSize least{.vertices = static_cast<std::int64_t>(cells), .cells = static_cast<std::int64_t>(cells), .nodes_per_cell = 8};
    check_memory(least, solver == "auto" ? auto_linear_solver(3 * least.vertices, true) : solver,
                 fmt::format("{}: a lattice at resolution {} (at least {:.3g} cells)", where, f.resolution, cells));
    const std::vector<char> used = used_vertices(m);
    lattices = build_solid_lattices(f, spec.join_meshes ? std::vector<int>(m.parts.size(), 0) : solids_of_parts(m, used), used,
                                    spec.split_cells ? 4 : 0);
    if (f.copied_vertices == 0) lattices = {};
  } else {
    f.cell_size = longest / f.resolution;
    // No tet larger than a sixth of a cube of the lattice's size (the five or six tets a cube splits into).
    MeshFile tets = tetrahedralize(SurfaceMesh{m.surface_vertices, m.surface_triangles, {}}, spec.model,
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
  // Where meshes are kept apart, a solid is held only by the bones of the joints its skin is weighted to.
  std::vector<std::vector<char>> solid_has_joint;
  if (!f.solid_of_volume_vertex.empty()) {
    solid_has_joint.assign(f.solids.size(), std::vector<char>(static_cast<std::size_t>(m.skeleton.size()), 0));
    for (Eigen::Index v = 0; v < m.vertices.cols(); ++v)
      for (int k = 0; k < 4; ++k)
        if (m.joint_weight(k, v) > 0.0)
          solid_has_joint[static_cast<std::size_t>(f.solid_of_point[static_cast<std::size_t>(v)])][static_cast<std::size_t>(m.joint_index(k, v))] = 1;
  }
  const BoneAccess may = solid_has_joint.empty() ? BoneAccess{} : [&](Eigen::Index v, int b) {
    return solid_has_joint[static_cast<std::size_t>(f.solid_of_volume_vertex[static_cast<std::size_t>(v)])]
                          [static_cast<std::size_t>(f.bones[static_cast<std::size_t>(b)].joint)] != 0;
  };
  f.binding = bind_to_bones(f.bones, f.volume.vertices, may);
  if (!lattices.lattice.empty()) f.binding = keep_bound_material(f.binding, f.bones, lattices, f.volume.vertex_count());
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
  if (spec.soft_shell > 0.0) f.soft = soft_bind_to_bones(f.bones, f.volume.vertices, spec.soft_shell, f.binding, may);
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

PressedFlesh pressed_flesh(const std::shared_ptr<const Flesh>& flesh, const std::vector<double>& times) {
  PressedFlesh out;
  const double h = flesh->cell_size, near = 0.5 * h, apart = 2.0 * h * (1.0 - 1e-9);  // two lattice cells apart count, to rounding
  const Binding& bound = flesh->binding;
  if (bound.vertex.empty() || !(h > 0.0)) return out;
  const Eigen::MatrixXi& cells = flesh->volume.cells;
  // The bound vertices at the border of their joint's bound flesh (sharing a cell with a vertex that joint does
  // not hold): where two joints' bound flesh overlaps, the border of one passes through the other (or lies wholly
  // inside it), so overlaps show at borders. Only those are asked for neighbours, among all bound vertices.
  const std::vector<int> joint_of = bound_joints(bound, flesh->bones, flesh->volume.vertex_count());
  std::vector<char> border(joint_of.size(), 0);
  for (Eigen::Index c = 0; c < cells.cols(); ++c)
    for (Eigen::Index a = 0; a < cells.rows(); ++a)
      for (Eigen::Index b = 0; b < cells.rows(); ++b)
        if (const int j = joint_of[static_cast<std::size_t>(cells(a, c))]; j >= 0 && joint_of[static_cast<std::size_t>(cells(b, c))] != j)
          border[static_cast<std::size_t>(cells(a, c))] = 1;
  const BoneCarried carried(flesh, bound);
  const auto n = static_cast<Eigen::Index>(bound.vertex.size());
  auto vertex = [&](Eigen::Index i) { return bound.vertex[static_cast<std::size_t>(i)]; };
  Eigen::Matrix3Xd at;
  Eigen::Matrix<std::int64_t, 3, Eigen::Dynamic> cell(3, n);
  std::vector<std::pair<std::int64_t, int>> grid(bound.vertex.size());  // (cube of side `near`, vertex), sorted
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) { return (x << 42) | (y << 21) | z; };
  for (std::size_t k = 0; k < times.size(); ++k) {
    carried.at(times[k], at);
    const Eigen::Vector3d lo = at.rowwise().minCoeff().array() - near;  // every cube index >= 1
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int d = 0; d < 3; ++d) cell(d, i) = static_cast<std::int64_t>(std::floor((at(d, i) - lo(d)) / near));
      grid[static_cast<std::size_t>(i)] = {key(cell(0, i), cell(1, i), cell(2, i)), static_cast<int>(i)};
    }
    std::sort(grid.begin(), grid.end());
    bool pressed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!border[static_cast<std::size_t>(vertex(i))]) continue;
      const int ji = joint_of[static_cast<std::size_t>(vertex(i))];
      for (std::int64_t dx = -1; dx <= 1; ++dx)
        for (std::int64_t dy = -1; dy <= 1; ++dy) {  // the three cubes along z have consecutive keys
          const std::int64_t first = key(cell(0, i) + dx, cell(1, i) + dy, cell(2, i) - 1), last = first + 2;
          for (auto it = std::lower_bound(grid.begin(), grid.end(), std::pair<std::int64_t, int>{first, 0});
               it != grid.end() && it->first <= last; ++it) {
            const int j = it->second;
            if (joint_of[static_cast<std::size_t>(vertex(j))] == ji) continue;
            const double d = (at.col(i) - at.col(j)).norm();
            const double rest = (flesh->volume.vertices.col(vertex(i)) - flesh->volume.vertices.col(vertex(j))).norm();
            if (d >= near || rest < apart) continue;
            pressed = true;
            if (out.frame >= 0 && d / rest >= out.closest / out.rest) continue;  // not worse than the worst so far
            out.frame = static_cast<int>(k);
            out.time = times[k];
            out.bone_a = bound.bone[static_cast<std::size_t>(i)];
            out.bone_b = bound.bone[static_cast<std::size_t>(j)];
            out.rest = rest;
            out.closest = d;
          }
        }
    }
    out.frames += pressed ? 1 : 0;
  }
  return out;
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
  // Where meshes are kept apart, the nearest model vertex of the volume vertex's own solid.
  const std::vector<int>& solid = flesh->solid_of_volume_vertex;
  const std::vector<int>& solid_of_point = flesh->solid_of_point;
#pragma omp parallel for schedule(static)
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Index nearest = 0;
    if (solid.empty()) {
      (S.colwise() - X.col(v)).colwise().squaredNorm().minCoeff(&nearest);
    } else {
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index p = 0; p < S.cols(); ++p)
        if (solid_of_point[static_cast<std::size_t>(p)] == solid[static_cast<std::size_t>(v)])
          if (const double d = (S.col(p) - X.col(v)).squaredNorm(); d < best) best = d, nearest = p;
    }
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
