#include "core/mesh/boundary.h"

#include <algorithm>
#include <utility>

namespace organsim {

namespace {

// The four faces of a positively oriented tet (p0, p1, p2, p3), each listed
// counter-clockwise seen from outside: face i is opposite vertex i. For the
// unit tet (0, e1, e2, e3), (e2-e1)x(e3-e1) = (1,1,1) points away from p0.
constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct FaceKey {
  std::array<int32_t, 3> sorted;  // vertex ids ascending: the face's identity
  Tri oriented;                   // as the owning tet sees it
  int32_t tet;                    // the owning tet's index
};

}  // namespace

std::vector<Tri> extract_boundary_faces(const std::vector<Tet>& tets, std::vector<int32_t>* owner) {
  std::vector<FaceKey> keys;
  keys.reserve(tets.size() * 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    const Tet& tet = tets[t];
    for (const auto& f : kTetFace) {
      Tri tri{tet[f[0]], tet[f[1]], tet[f[2]]};
      std::array<int32_t, 3> sorted = tri;
      std::sort(sorted.begin(), sorted.end());
      keys.push_back({sorted, tri, static_cast<int32_t>(t)});
    }
  }
  // Sorting groups the copies of each interior face (two tets) next to each
  // other; a face seen once is on the boundary. Sorting also makes the output
  // order independent of the tet order.
  std::sort(keys.begin(), keys.end(),
            [](const FaceKey& a, const FaceKey& b) { return a.sorted < b.sorted; });
  std::vector<Tri> boundary;
  if (owner) owner->clear();
  for (size_t i = 0; i < keys.size();) {
    size_t j = i + 1;
    while (j < keys.size() && keys[j].sorted == keys[i].sorted) ++j;
    if (j - i == 1) {
      boundary.push_back(keys[i].oriented);
      if (owner) owner->push_back(keys[i].tet);
    }
    i = j;
  }
  return boundary;
}

std::vector<Edge> edges_between_face_groups(const std::vector<Tri>& faces, const std::vector<int32_t>& group) {
  // Each face's three edges with its group; an edge whose faces are not all
  // of one group separates two groups.
  std::vector<std::pair<Edge, int32_t>> half;
  half.reserve(faces.size() * 3);
  for (size_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = faces[f][k], b = faces[f][(k + 1) % 3];
      half.push_back({Edge{std::min(a, b), std::max(a, b)}, group[f]});
    }
  }
  std::sort(half.begin(), half.end());
  std::vector<Edge> between;
  for (size_t i = 0; i < half.size();) {
    size_t j = i + 1;
    while (j < half.size() && half[j].first == half[i].first) ++j;
    if (half[j - 1].second != half[i].second) between.push_back(half[i].first);  // sorted: first != last
    i = j;
  }
  return between;
}

double enclosed_volume(const std::vector<Vec3>& points, const std::vector<Tri>& faces) {
  double six_volume = 0;
  for (const Tri& f : faces) {
    six_volume += points[f[0]].dot(points[f[1]].cross(points[f[2]]));
  }
  return six_volume / 6.0;
}

SurfaceTopology surface_topology(const std::vector<Tri>& faces) {
  SurfaceTopology topo;
  topo.faces = static_cast<int64_t>(faces.size());
  // Directed half-edges (a, b); an edge is the pair sorted.
  std::vector<std::pair<Edge, bool>> half;  // (sorted edge, a < b as traversed)
  std::vector<int32_t> used;
  half.reserve(faces.size() * 3);
  used.reserve(faces.size() * 3);
  for (const Tri& f : faces) {
    for (int k = 0; k < 3; ++k) {
      const int32_t a = f[k], b = f[(k + 1) % 3];
      half.push_back({Edge{std::min(a, b), std::max(a, b)}, a < b});
      used.push_back(a);
    }
  }
  std::sort(used.begin(), used.end());
  topo.vertices = std::unique(used.begin(), used.end()) - used.begin();
  std::sort(half.begin(), half.end());
  for (size_t i = 0; i < half.size();) {
    size_t j = i + 1;
    while (j < half.size() && half[j].first == half[i].first) ++j;
    ++topo.edges;
    const size_t count = j - i;
    if (count == 1) ++topo.border_edges;
    if (count > 2) ++topo.nonmanifold_edges;
    // Sorted by (edge, direction): two faces agree in orientation when they
    // traverse the shared edge in opposite directions.
    if (count == 2 && half[i].second == half[i + 1].second) ++topo.misoriented_edges;
    i = j;
  }
  return topo;
}

void vertex_normals(const std::vector<Vec3>& points, const std::vector<Tri>& faces,
                    std::vector<Vec3>& normals) {
  normals.assign(points.size(), Vec3::Zero());
  for (const Tri& f : faces) {
    // The cross product's length is twice the area: area weighting for free.
    const Vec3 n = (points[f[1]] - points[f[0]]).cross(points[f[2]] - points[f[0]]);
    for (int k = 0; k < 3; ++k) normals[f[k]] += n;
  }
  for (Vec3& n : normals) {
    const double len = n.norm();
    if (len > 0) n /= len;
  }
}

}  // namespace organsim
