#include "snh/mesh/surface.hpp"

#include <algorithm>
#include <array>
#include <unordered_map>
#include <utility>
#include <vector>

namespace snh {
namespace {

// Local faces, outward for a positively oriented tet and for the hex corner order of VolumeMesh.
constexpr int kTetFaces[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
constexpr int kHexFaces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};

template <std::size_t N>
struct FaceKey {
  std::array<int, N> v;
  bool operator==(const FaceKey& o) const { return v == o.v; }
};
template <std::size_t N>
struct FaceHash {
  std::size_t operator()(const FaceKey<N>& k) const {
    std::size_t h = 1469598103934665603ull;
    for (int x : k.v) h = (h ^ static_cast<std::size_t>(x)) * 1099511628211ull;
    return h;
  }
};

/// Faces (each with N corners) that occur in exactly one cell, in first-seen order, with that cell.
template <std::size_t N, std::size_t F>
std::vector<std::pair<std::array<int, N>, int>> unique_faces(const VolumeMesh& mesh, const int (&local)[F][N]) {
  std::unordered_map<FaceKey<N>, int, FaceHash<N>> count;
  std::vector<std::array<int, N>> faces;
  faces.reserve(static_cast<std::size_t>(mesh.cell_count()) * F);
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c)
    for (const auto& f : local) {
      std::array<int, N> face{};
      for (std::size_t a = 0; a < N; ++a) face[a] = mesh.cells(f[a], c);
      FaceKey<N> key{face};
      std::sort(key.v.begin(), key.v.end());
      ++count[key];
      faces.push_back(face);
    }
  std::vector<std::pair<std::array<int, N>, int>> out;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    FaceKey<N> key{faces[i]};
    std::sort(key.v.begin(), key.v.end());
    if (count[key] == 1) out.emplace_back(faces[i], static_cast<int>(i / F));
  }
  return out;
}

}  // namespace

Eigen::Matrix3Xi boundary_triangles(const VolumeMesh& mesh, std::vector<int>* cells) {
  if (cells) cells->clear();
  if (mesh.type == CellType::tet4) {
    const auto faces = unique_faces(mesh, kTetFaces);
    Eigen::Matrix3Xi T(3, faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const auto& [t, cell] = faces[f];
      T.col(f) << t[0], t[1], t[2];
      if (cells) cells->push_back(cell);
    }
    return T;
  }
  const auto quads = unique_faces(mesh, kHexFaces);
  Eigen::Matrix3Xi T(3, 2 * quads.size());
  for (std::size_t f = 0; f < quads.size(); ++f) {
    const auto& [q, cell] = quads[f];
    T.col(2 * f) << q[0], q[1], q[2];
    T.col(2 * f + 1) << q[0], q[2], q[3];
    if (cells) cells->insert(cells->end(), {cell, cell});
  }
  return T;
}

EdgeCounts edge_counts(const Eigen::Matrix3Xi& F) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * F.cols());
  for (Eigen::Index f = 0; f < F.cols(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(k, f), b = F((k + 1) % 3, f);
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  EdgeCounts c;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    ++c.edges;
    if (j - i == 1) ++c.open;
    else if (j - i > 2) ++c.non_manifold;
    i = j;
  }
  return c;
}

}  // namespace snh
