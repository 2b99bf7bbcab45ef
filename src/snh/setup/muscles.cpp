#include "snh/setup/muscles.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <limits>
#include <map>
#include <stdexcept>

#include <Eigen/SparseCholesky>
#include <fmt/format.h>

#include "snh/contact/box_tree.hpp"
#include "snh/embed/winding_number.hpp"
#include "snh/fem/rest_state.hpp"
#include "snh/io/input_file.hpp"
#include "snh/math/union_find.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/mesh/surface.hpp"
#include "snh/setup/flesh.hpp"
#include "snh/setup/scene_build.hpp"

namespace snh {
namespace {

/// Volume vertices carried rigidly by one joint's motion from the bind pose (a bone tissue).
class JointCarried final : public KinematicProvider {
 public:
  JointCarried(std::shared_ptr<const Flesh> flesh, int joint, Eigen::Matrix3Xd rest)
      : flesh_(std::move(flesh)), joint_(joint), rest_(std::move(rest)) {}
  void targets(double t, Eigen::Matrix3Xd& out) const override {
    const auto j = static_cast<std::size_t>(joint_);
    const Eigen::Affine3d motion = joint_world(*flesh_, t)[j] * flesh_->bind_world[j].inverse();
    out = motion * rest_;
  }

 private:
  std::shared_ptr<const Flesh> flesh_;
  int joint_;
  Eigen::Matrix3Xd rest_;
};

/// A point's rest position: given, or its joint's position at the bind pose. Throws RigError for a joint the
/// model lacks (build_scene makes it a SceneError).
Eigen::Vector3d rest_point(const MusclePoint& p, const Flesh* flesh, const std::string& where) {
  if (p.point) return *p.point;
  const int j = joint_named(flesh->model, p.joint, where);
  return flesh->bind_world[static_cast<std::size_t>(j)].translation();
}

/// Piecewise linear through the keys, held before the first and after the last.
double keyed(const std::vector<ActivationKey>& keys, double t) {
  if (keys.empty()) return 0.0;
  if (t <= keys.front().time) return keys.front().value;
  if (t >= keys.back().time) return keys.back().value;
  const auto hi = std::upper_bound(keys.begin(), keys.end(), t, [](double x, const ActivationKey& k) { return x < k.time; });
  const auto lo = hi - 1;
  const double s = (t - lo->time) / (hi->time - lo->time);
  return lo->value + s * (hi->value - lo->value);
}

/// Per cell, the mean of its vertices at rest.
Eigen::Matrix3Xd cell_centres(const VolumeMesh& mesh) {
  Eigen::Matrix3Xd c = Eigen::Matrix3Xd::Zero(3, mesh.cell_count());
  for (Eigen::Index e = 0; e < mesh.cell_count(); ++e) {
    for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) c.col(e) += mesh.vertices.col(mesh.cells(k, e));
    c.col(e) /= static_cast<double>(mesh.cells.rows());
  }
  return c;
}

/// Every edge in exactly two triangles.
bool closed_surface(const Eigen::Matrix3Xi& F) {
  const EdgeCounts e = edge_counts(F);
  return e.open == 0 && e.non_manifold == 0;
}

/// The cells of `mesh` whose centre the surface (V, F) holds: winding number of magnitude ≥ ½ (either
/// orientation; holes tolerated). On a closed surface (`closed`: every edge in two triangles) the winding
/// number is constant off the surface, so it is asked once per group of cells that no triangle's box
/// touches and that share vertices (convex cells: the path between two centres through a shared vertex
/// stays in the two cells), and at each cell a triangle's box touches; on an open one at every cell.
std::vector<int> cells_inside_at(const VolumeMesh& mesh, const Eigen::Matrix3Xd& centres, const Eigen::Matrix3Xd& V,
                                 const Eigen::Matrix3Xi& F, bool closed) {
  std::vector<int> out;
  if (F.cols() == 0) return out;
  check_triangles(V, F);  // below, winding_number cannot throw
  const Eigen::Vector3d lo = V.rowwise().minCoeff(), hi = V.rowwise().maxCoeff();
  const auto C = static_cast<std::size_t>(mesh.cell_count());
  const auto in_box = [&](const Eigen::Vector3d& p) { return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all(); };
  std::vector<double> winding(C, 0.0);
  std::vector<int> asked;  // the cells whose winding number is computed
  UnionFind groups(C);  // cells no triangle touches, joined where they share a vertex
  std::vector<char> touched(C, 0), group_outside(C, 0);
  if (!closed) {
    for (std::size_t c = 0; c < C; ++c)
      if (in_box(centres.col(static_cast<Eigen::Index>(c)))) asked.push_back(static_cast<int>(c));
  } else {
    Eigen::Matrix3Xd tlo(3, F.cols()), thi(3, F.cols());
    for (Eigen::Index t = 0; t < F.cols(); ++t) {
      tlo.col(t) = V(Eigen::all, F.col(t)).rowwise().minCoeff();
      thi.col(t) = V(Eigen::all, F.col(t)).rowwise().maxCoeff();
    }
    const contact::BoxTree tree(tlo, thi);
    std::vector<int> at_vertex(static_cast<std::size_t>(mesh.vertex_count()), -1);
    std::vector<char> outside(C, 0);
    for (std::size_t c = 0; c < C; ++c) {
      const auto nodes = mesh.vertices(Eigen::all, mesh.cells.col(static_cast<Eigen::Index>(c)));
      const Eigen::Vector3d clo = nodes.rowwise().minCoeff(), chi = nodes.rowwise().maxCoeff();
      outside[c] = (chi.array() < lo.array()).any() || (clo.array() > hi.array()).any();
      if (outside[c]) continue;
      for (int t : tree.near(clo, chi))  // the tree's answer is a superset: each triangle's own box decides
        if ((tlo.col(t).array() <= chi.array()).all() && (thi.col(t).array() >= clo.array()).all()) {
          touched[c] = 1;
          break;
        }
    }
    for (std::size_t c = 0; c < C; ++c) {
      if (touched[c]) {
        asked.push_back(static_cast<int>(c));
        continue;
      }
      for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) {
        int& first = at_vertex[static_cast<std::size_t>(mesh.cells(k, static_cast<Eigen::Index>(c)))];
        if (first < 0) first = static_cast<int>(c);
        else groups.join(static_cast<int>(c), first);
      }
    }
    // Per group: outside the surface's box if any of its cells is, else the winding number at one of them.
    std::vector<char> group_asked(C, 0);
    for (std::size_t c = 0; c < C; ++c)
      if (!touched[c] && outside[c]) group_outside[static_cast<std::size_t>(groups.root(static_cast<int>(c)))] = 1;
    for (std::size_t c = 0; c < C; ++c) {
      const auto r = static_cast<std::size_t>(groups.root(static_cast<int>(c)));
      if (!touched[c] && !group_outside[r] && !group_asked[r]) group_asked[r] = 1, asked.push_back(static_cast<int>(r));
    }
  }
  const auto n = static_cast<long>(asked.size());
#pragma omp parallel for schedule(dynamic, 16)
  for (long i = 0; i < n; ++i) {
    const auto c = static_cast<std::size_t>(asked[static_cast<std::size_t>(i)]);
    const Eigen::Vector3d p = centres.col(static_cast<Eigen::Index>(c));
    if (in_box(p)) winding[c] = winding_number(V, F, p);
  }
  for (std::size_t c = 0; c < C; ++c) {
    double w = winding[c];
    if (closed && !touched[c]) {
      const auto r = static_cast<std::size_t>(groups.root(static_cast<int>(c)));
      w = group_outside[r] ? 0.0 : winding[r];
    }
    if (std::abs(w) >= 0.5) out.push_back(static_cast<int>(c));
  }
  return out;
}

/// The cells of region `r` (entry `where`); `tags`: the mesh file's cell tags (empty: none).
std::vector<int> region_cells(const RegionSpec& r, const VolumeMesh& mesh, const Eigen::Matrix3Xd& centres, const Flesh* flesh, const std::vector<long long>& tags,
                              const std::string& where) {
  std::vector<int> out;
  switch (r.kind) {
    case RegionSpec::Kind::tags: {
      if (tags.empty())
        throw SceneError(fmt::format("{}.region.tags: the mesh has no cell tags (MEDIT references, Gmsh physical or entity tags, "
                                     "TetGen region attributes)",
                                     where));
      for (std::size_t c = 0; c < tags.size(); ++c)
        if (std::find(r.tags.begin(), r.tags.end(), tags[c]) != r.tags.end()) out.push_back(static_cast<int>(c));
      if (out.empty()) {
        std::vector<long long> have(tags.begin(), tags.end());
        std::sort(have.begin(), have.end());
        have.erase(std::unique(have.begin(), have.end()), have.end());
        std::string list;
        for (std::size_t i = 0; i < have.size() && i < 12; ++i) list += fmt::format("{}{}", i ? ", " : "", have[i]);
        if (have.size() > 12) list += ", …";
        throw SceneError(fmt::format("{}.region.tags: no cell has these tags (the mesh's cells have: {})", where, list));
      }
      return out;
    }
    case RegionSpec::Kind::box:
      for (Eigen::Index c = 0; c < centres.cols(); ++c)
        if (r.box.contains(centres.col(c))) out.push_back(static_cast<int>(c));
      return out;
    case RegionSpec::Kind::mesh: {
      SurfaceMesh s;
      if (const std::string problem = input_file_problem(r.file, "region mesh"); !problem.empty())
        throw SceneError(fmt::format("{}.region.mesh: {}", where, problem));
      try {
        s = read_surface(r.file);
        check_triangles(s.vertices, s.triangles);
      } catch (const std::exception& e) {
        throw SceneError(fmt::format("{}.region.mesh: {}", where, e.what()));
      }
      if (s.triangles.cols() == 0) throw SceneError(fmt::format("{}.region.mesh: {} has no triangles", where, r.file.string()));
      return cells_inside_at(mesh, centres, s.vertices, s.triangles, closed_surface(s.triangles));
    }
    case RegionSpec::Kind::model_mesh: {
      const RiggedModel& m = flesh->model;
      const auto part = std::find_if(m.parts.begin(), m.parts.end(), [&](const ModelPart& p) { return p.name == r.model_mesh; });
      if (part == m.parts.end()) {
        std::string list;
        for (const ModelPart& p : m.parts) list += (list.empty() ? "" : ", ") + p.name;
        throw SceneError(fmt::format("{}.region.model_mesh: no mesh named \"{}\" in the model (its meshes: {})", where, r.model_mesh, list));
      }
      std::vector<Eigen::Index> tris;
      for (Eigen::Index t = 0; t < m.triangles.cols(); ++t)
        if (m.triangles(0, t) >= part->first_vertex && m.triangles(0, t) < part->first_vertex + part->vertices) tris.push_back(t);
      // Closed as welded (texture seams split the model's own vertices).
      Eigen::Matrix3Xi welded(3, static_cast<Eigen::Index>(tris.size()));
      for (std::size_t t = 0; t < tris.size(); ++t)
        for (int k = 0; k < 3; ++k) welded(k, static_cast<Eigen::Index>(t)) = m.weld[static_cast<std::size_t>(m.triangles(k, tris[t]))];
      return cells_inside_at(mesh, centres, m.surface_vertices, welded, closed_surface(welded));
    }
  }
  return out;
}

/// The fibres of a file: one line "ax ay az" per cell of `mesh` ('#' starts a comment; blank lines are
/// skipped). Throws SceneError naming the file and line: a line that is not three finite numbers, a zero
/// direction, another count of lines than of cells.
std::vector<Eigen::Vector3d> fibres_of_file(const std::filesystem::path& file, const VolumeMesh& mesh, const std::string& where) {
  if (const std::string problem = input_file_problem(file, "fibre file"); !problem.empty())
    throw SceneError(fmt::format("{}: fibre.file: {}", where, problem));
  std::ifstream in(file);
  if (!in) throw SceneError(fmt::format("{}: fibre.file: {}: cannot be opened", where, file.string()));
  std::vector<Eigen::Vector3d> out;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (const auto hash = text.find('#'); hash != std::string::npos) text.resize(hash);
    std::istringstream s(text);
    Eigen::Vector3d a;
    std::string rest;
    if (!(s >> std::ws) || s.eof()) continue;  // blank
    if (!(s >> a[0] >> a[1] >> a[2]) || (s >> rest) || !a.allFinite())
      throw SceneError(fmt::format("{}:{}: expected three finite numbers (a fibre direction), got \"{}\"", file.string(), line, text));
    if (!(a.norm() > 0.0)) throw SceneError(fmt::format("{}:{}: a fibre direction must not be zero", file.string(), line));
    if (static_cast<Eigen::Index>(out.size()) == mesh.cell_count())
      throw SceneError(fmt::format("{}:{}: more directions than the volume's {} cells", file.string(), line, mesh.cell_count()));
    out.push_back(a.normalized());
  }
  if (static_cast<Eigen::Index>(out.size()) != mesh.cell_count())
    throw SceneError(fmt::format("{}: {} directions for the volume's {} cells (one line per cell, in cell order)", file.string(), out.size(),
                                 mesh.cell_count()));
  return out;
}

/// The activation of a line of action (LineOfAction) on the flesh's joints; `line` gets its header clause.
std::function<double(double)> line_activation(const LineOfAction& l, const std::shared_ptr<const Flesh>& flesh, const std::string& where,
                                              std::string& line) {
  const int jf = joint_named(flesh->model, l.from.joint, where + ": activation.line_of_action.from");
  const int jt = joint_named(flesh->model, l.to.joint, where + ": activation.line_of_action.to");
  const Eigen::Vector3d pf = rest_point(l.from, flesh.get(), where), pt = rest_point(l.to, flesh.get(), where);
  const double rest_length = (pt - pf).norm();
  if (!(rest_length > 0.0)) throw SceneError(fmt::format("{}: activation.line_of_action: from and to are the same point at rest", where));
  // The points in their joints' frames at the bind pose.
  const Eigen::Vector3d lf = flesh->bind_world[static_cast<std::size_t>(jf)].inverse() * pf;
  const Eigen::Vector3d lt = flesh->bind_world[static_cast<std::size_t>(jt)].inverse() * pt;
  line += fmt::format(", activation by the line of action {} → {} (rest length {:.4g}, gain {:g}, at most {:g})", l.from.joint, l.to.joint,
                      rest_length, l.gain, l.max);
  return [flesh, jf, jt, lf, lt, rest_length, l](double t) {
    const std::vector<Eigen::Affine3d> world = joint_world(*flesh, t);
    const double length = (world[static_cast<std::size_t>(jt)] * lt - world[static_cast<std::size_t>(jf)] * lf).norm();
    return std::clamp(l.gain * (1.0 - length / rest_length), 0.0, l.max);
  };
}

}  // namespace

std::vector<int> cells_inside(const VolumeMesh& mesh, const Eigen::Matrix3Xd& V, const Eigen::Matrix3Xi& F) {
  return cells_inside_at(mesh, cell_centres(mesh), V, F, closed_surface(F));
}

std::vector<int> attachment_vertices(const VolumeMesh& mesh, const std::vector<int>& cells, const Eigen::Vector3d& point,
                                     double reach) {
  std::vector<int> vertices;
  for (int c : cells)
    for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) vertices.push_back(mesh.cells(k, c));
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  double nearest = std::numeric_limits<double>::infinity();
  for (int v : vertices) nearest = std::min(nearest, (mesh.vertices.col(v) - point).norm());
  std::vector<int> out;
  for (int v : vertices)
    if ((mesh.vertices.col(v) - point).norm() <= nearest + reach) out.push_back(v);
  return out;
}

std::vector<Eigen::Vector3d> harmonic_fibres(const VolumeMesh& mesh, const std::vector<int>& cells, const std::vector<int>& origin,
                                             const std::vector<int>& insertion, const Eigen::Vector3d& fallback) {
  if (origin.empty() || insertion.empty()) throw std::invalid_argument("a harmonic field needs vertices at both ends");
  // The cells' own mesh, its vertices numbered anew.
  std::map<int, int> local;
  VolumeMesh sub;
  sub.type = mesh.type;
  sub.cells.resize(mesh.cells.rows(), static_cast<Eigen::Index>(cells.size()));
  for (std::size_t c = 0; c < cells.size(); ++c)
    for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) {
      const int v = mesh.cells(k, cells[c]);
      const auto [it, fresh] = local.emplace(v, static_cast<int>(local.size()));
      sub.cells(k, static_cast<Eigen::Index>(c)) = it->second;
    }
  sub.vertices.resize(3, static_cast<Eigen::Index>(local.size()));
  for (const auto& [v, i] : local) sub.vertices.col(i) = mesh.vertices.col(v);
  const Eigen::Index n = sub.vertex_count();
  std::vector<double> fixed(static_cast<std::size_t>(n), -1.0);  // −1: free; else u's value
  const auto mark = [&](const std::vector<int>& ends, double value) {
    for (int v : ends) {
      const auto it = local.find(v);
      if (it == local.end()) throw std::invalid_argument(fmt::format("vertex {} of an end is not in the region", v));
      double& f = fixed[static_cast<std::size_t>(it->second)];
      if (f >= 0.0 && f != value)
        throw std::invalid_argument(fmt::format(
            "the region's ends at the origin and the insertion meet (at the vertex at ({:.4g}, {:.4g}, {:.4g})): place them further "
            "apart or give a smaller reach",
            mesh.vertices(0, v), mesh.vertices(1, v), mesh.vertices(2, v)));
      f = value;
    }
  };
  mark(origin, 0.0);
  mark(insertion, 1.0);
  std::vector<int> free_index(static_cast<std::size_t>(n), -1);
  int free = 0;
  for (Eigen::Index v = 0; v < n; ++v)
    if (fixed[static_cast<std::size_t>(v)] < 0.0) free_index[static_cast<std::size_t>(v)] = free++;
  // K u = 0 on the free vertices: K_ff u_f = −K_fd u_d, K = Σ_q w_q G_q G_qᵀ per cell.
  const RestState rest = compute_rest_state(sub);
  std::vector<Eigen::Triplet<double>> triplets;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(free);
  double diagonal = 0.0;
  std::visit(
      [&](const auto& records) {
        for (std::size_t c = 0; c < records.size(); ++c) {
          const auto& r = records[c];
          for (std::size_t q = 0; q < r.weight.size(); ++q) {
            const auto K = (r.weight[q] * r.G[q] * r.G[q].transpose()).eval();
            for (Eigen::Index a = 0; a < K.rows(); ++a) {
              const int va = sub.cells(a, static_cast<Eigen::Index>(c)), fa = free_index[static_cast<std::size_t>(va)];
              if (fa < 0) continue;
              diagonal = std::max(diagonal, K(a, a));
              for (Eigen::Index b = 0; b < K.cols(); ++b) {
                const int vb = sub.cells(b, static_cast<Eigen::Index>(c)), fb = free_index[static_cast<std::size_t>(vb)];
                if (fb >= 0) triplets.emplace_back(fa, fb, K(a, b));
                else rhs[fa] -= K(a, b) * fixed[static_cast<std::size_t>(vb)];
              }
            }
          }
        }
      },
      rest);
  // A part of the region that touches neither end is held at 0 by a slight spring (its fibres then fall back
  // to the axis below).
  for (int f = 0; f < free; ++f) triplets.emplace_back(f, f, 1e-12 * std::max(diagonal, 1e-300));
  Eigen::SparseMatrix<double> K(free, free);
  K.setFromTriplets(triplets.begin(), triplets.end());
  Eigen::VectorXd uf = Eigen::VectorXd::Zero(free);
  if (free > 0) {
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K);
    if (ldlt.info() != Eigen::Success) throw std::invalid_argument("the Laplace system of the fibre field could not be factored");
    uf = ldlt.solve(rhs);
  }
  Eigen::VectorXd u(n);
  for (Eigen::Index v = 0; v < n; ++v)
    u[v] = free_index[static_cast<std::size_t>(v)] >= 0 ? uf[free_index[static_cast<std::size_t>(v)]] : fixed[static_cast<std::size_t>(v)];
  // Each cell's gradient: the quadrature points' mean, weighted.
  std::vector<Eigen::Vector3d> out(cells.size(), fallback);
  const Eigen::Vector3d lo = sub.vertices.rowwise().minCoeff(), hi = sub.vertices.rowwise().maxCoeff();
  const double slope = 1e-6 / std::max((hi - lo).norm(), 1e-300);  // far below any slope from end to end
  std::visit(
      [&](const auto& records) {
        for (std::size_t c = 0; c < records.size(); ++c) {
          const auto& r = records[c];
          Eigen::Vector3d g = Eigen::Vector3d::Zero();
          double w = 0.0;
          for (std::size_t q = 0; q < r.weight.size(); ++q) {
            for (Eigen::Index a = 0; a < r.G[q].rows(); ++a)
              g += r.weight[q] * u[sub.cells(a, static_cast<Eigen::Index>(c))] * r.G[q].row(a).transpose();
            w += r.weight[q];
          }
          g /= w;
          if (g.norm() > slope && g.allFinite()) out[c] = g.normalized();
        }
      },
      rest);
  return out;
}

std::vector<double> BuiltMuscles::activation(double t) const {
  std::vector<double> a;
  for (const Muscle& m : muscles) a.push_back(m.activation(t));
  return a;
}

void BuiltMuscles::fibre_strain(double t, std::vector<double>& alpha) const {
  alpha.assign(fibres.size(), 0.0);
  for (const Muscle& m : muscles) {
    const double value = m.contraction * m.activation(t);
    for (int f = m.first_fibre; f < m.first_fibre + m.fibre_count; ++f) alpha[static_cast<std::size_t>(f)] = value;
  }
}

nlohmann::json muscles_json(const BuiltMuscles& m, const Scene& scene, const VolumeMesh& mesh, const std::vector<double>& times) {
  using json = nlohmann::json;
  const Eigen::Matrix3Xd centres = cell_centres(mesh);
  json regions = json::array();
  for (std::size_t i = 0; i < scene.muscles.size(); ++i) {
    const MuscleSpec& spec = scene.muscles[i];
    json cells = json::array();
    for (std::size_t c = 0; c < m.region_of_cell.size(); ++c)
      if (m.region_of_cell[c] == static_cast<int>(i)) cells.push_back(c);
    json r = {{"name", spec.name}, {"kind", spec.muscle ? "muscle" : "tissue"}, {"cells", cells}};
    if (!spec.bone.empty()) r["bone"] = spec.bone;
    regions.push_back(std::move(r));
  }
  for (const BuiltMuscles::Muscle& muscle : m.muscles) {
    json& r = regions[static_cast<std::size_t>(muscle.spec)];
    json centre = json::array(), direction = json::array(), activation = json::array();
    for (const json& c : r["cells"]) {
      const auto cell = c.get<Eigen::Index>();
      const Vec3& a = m.fibres[static_cast<std::size_t>(m.fibre_of_cell[static_cast<std::size_t>(cell)])].direction;
      centre.push_back({centres(0, cell), centres(1, cell), centres(2, cell)});
      direction.push_back({a[0], a[1], a[2]});
    }
    for (double t : times) activation.push_back(muscle.activation(t));
    r["contraction"] = muscle.contraction;
    r["fibre_centres"] = std::move(centre);
    r["fibre_directions"] = std::move(direction);
    r["times"] = times;
    r["activation"] = std::move(activation);
  }
  return {{"regions", regions}};
}

std::shared_ptr<const BuiltMuscles> build_muscles(const Scene& s, const SceneBody& body) {
  if (s.muscles.empty()) return nullptr;
  const std::string file = s.source.string();
  const VolumeMesh& mesh = body.mesh;
  const Flesh* flesh = body.flesh.get();
  auto out = std::make_shared<BuiltMuscles>();
  out->materials = {make_material(s.material.name, s.material.params, s.material.reparametrize)};
  out->material_of_cell.assign(static_cast<std::size_t>(mesh.cell_count()), 0);
  out->region_of_cell.assign(static_cast<std::size_t>(mesh.cell_count()), -1);
  const Eigen::Matrix3Xd centres = cell_centres(mesh);
  int tissues = 0, muscles = 0;
  std::vector<std::string> where(s.muscles.size());
  std::vector<int> material_of_entry(s.muscles.size(), 0);
  // Later entries take the cells they share with earlier ones.
  for (std::size_t i = 0; i < s.muscles.size(); ++i) {
    const MuscleSpec& m = s.muscles[i];
    where[i] = fmt::format("{}: {}[{}] \"{}\"", file, m.muscle ? "muscles" : "tissues", m.muscle ? muscles++ : tissues++, m.name);
    if (m.material) {
      material_of_entry[i] = static_cast<int>(out->materials.size());
      out->materials.push_back(make_material(m.material->name, m.material->params, m.material->reparametrize));
    }
    for (int c : region_cells(m.region, mesh, centres, flesh, body.cell_tags, where[i])) out->region_of_cell[static_cast<std::size_t>(c)] = static_cast<int>(i);
  }
  std::vector<std::vector<int>> cells_of(s.muscles.size());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    if (const int r = out->region_of_cell[static_cast<std::size_t>(c)]; r >= 0) {
      cells_of[static_cast<std::size_t>(r)].push_back(static_cast<int>(c));
      out->material_of_cell[static_cast<std::size_t>(c)] = material_of_entry[static_cast<std::size_t>(r)];
    }
  const Eigen::VectorXd volumes = [&] {
    Eigen::VectorXd v(mesh.cell_count());
    for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) v[c] = std::abs(cell_volume(mesh, c));
    return v;
  }();
  const double total_volume = volumes.sum();
  std::vector<bool> taken(static_cast<std::size_t>(mesh.vertex_count()), false);  // by the bones' binding or a bone tissue
  if (flesh)
    for (int v : flesh->binding.vertex) taken[static_cast<std::size_t>(v)] = true;
  for (std::size_t i = 0; i < s.muscles.size(); ++i) {
    const MuscleSpec& m = s.muscles[i];
    const std::vector<int>& cells = cells_of[i];
    if (cells.empty())
      throw SceneError(fmt::format("{}: the region holds no cell's centre{}", where[i],
                                   i + 1 < s.muscles.size() ? " (or later entries took all its cells)" : ""));
    double volume = 0.0;
    for (int c : cells) volume += volumes[c];
    const MaterialChoice& material = m.material ? *m.material : s.material;
    std::string line = fmt::format("{} {}: {} cells ({:.1f}% of the volume), material {} (mu {:g}, lambda {:g})",
                                   m.muscle ? "muscle" : "tissue", m.name, cells.size(), 100.0 * volume / total_volume, material.name,
                                   material.params.mu, material.params.lambda);
    if (!m.muscle) {
      if (!m.bone.empty()) {
        const int joint = joint_named(flesh->model, m.bone, where[i] + ": bone");
        KinematicSet set;
        set.name = where[i];
        for (int c : cells)
          for (Eigen::Index k = 0; k < mesh.cells.rows(); ++k) {
            const int v = mesh.cells(k, c);
            if (!taken[static_cast<std::size_t>(v)]) taken[static_cast<std::size_t>(v)] = true, set.vertices.push_back(v);
          }
        line += fmt::format(", {} vertices bound to {}", set.vertices.size(), m.bone);
        set.provider = std::make_shared<JointCarried>(body.flesh, joint, mesh.vertices(Eigen::all, set.vertices));
        if (!set.vertices.empty()) out->bones.push_back(std::move(set));
      }
      out->summary.push_back(line);
      continue;
    }
    // Fibres.
    if (out->fibre_of_cell.empty()) out->fibre_of_cell.assign(static_cast<std::size_t>(mesh.cell_count()), -1);
    BuiltMuscles::Muscle muscle;
    muscle.name = m.name;
    muscle.spec = static_cast<int>(i);
    muscle.contraction = m.contraction;
    muscle.first_fibre = static_cast<int>(out->fibres.size());
    FibreEnergy energy;
    energy.model = m.fibre_model;
    energy.stiffness = m.fibre_stiffness.value_or(material.params.mu);
    if (m.field == MuscleSpec::Field::constant) {
      out->fibres.push_back({m.direction, energy, {}});
      for (int c : cells) out->fibre_of_cell[static_cast<std::size_t>(c)] = muscle.first_fibre;
      line += fmt::format(", fibres along ({:.3g}, {:.3g}, {:.3g}) (", m.direction[0], m.direction[1], m.direction[2]);
    } else if (m.field == MuscleSpec::Field::file) {
      const std::vector<Eigen::Vector3d> all = fibres_of_file(m.fibre_file, mesh, where[i]);
      for (int c : cells) {
        out->fibre_of_cell[static_cast<std::size_t>(c)] = static_cast<int>(out->fibres.size());
        out->fibres.push_back({all[static_cast<std::size_t>(c)], energy, {}});
      }
      line += fmt::format(", fibres of {} (", m.fibre_file.string());
    } else {
      const Eigen::Vector3d o = rest_point(m.origin, flesh, where[i] + ": fibre.origin");
      const Eigen::Vector3d n = rest_point(m.insertion, flesh, where[i] + ": fibre.insertion");
      if (!((n - o).norm() > 0.0)) throw SceneError(fmt::format("{}: fibre: the origin and the insertion are the same point", where[i]));
      const double reach = m.reach.value_or(0.1 * (n - o).norm());
      std::vector<Eigen::Vector3d> field;
      try {
        field = harmonic_fibres(mesh, cells, attachment_vertices(mesh, cells, o, reach), attachment_vertices(mesh, cells, n, reach),
                                (n - o).normalized());
      } catch (const std::exception& e) {
        throw SceneError(fmt::format("{}: fibre: {}", where[i], e.what()));
      }
      for (std::size_t k = 0; k < cells.size(); ++k) {
        out->fibre_of_cell[static_cast<std::size_t>(cells[k])] = static_cast<int>(out->fibres.size());
        out->fibres.push_back({field[k], energy, {}});
      }
      line += fmt::format(", fibres of a harmonic field from origin to insertion (reach {:.3g}; ", reach);
    }
    muscle.fibre_count = static_cast<int>(out->fibres.size()) - muscle.first_fibre;
    line += fmt::format("{}, stiffness {:g}), contraction {:g}", to_string(m.fibre_model), energy.stiffness, m.contraction);
    if (m.line) {
      muscle.activation = line_activation(*m.line, body.flesh, where[i], line);
    } else {
      muscle.activation = [keys = m.keys](double t) { return keyed(keys, t); };
      line += m.keys.empty() ? ", never activated" : fmt::format(", activation by {} keys", m.keys.size());
    }
    out->muscles.push_back(std::move(muscle));
    out->summary.push_back(line);
  }
  return out;
}

}  // namespace snh
