#include "core/topology/point_split.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>
#include <string>

namespace organsim {

namespace {

bool contains(const Tet& tet, int32_t p) { return std::find(tet.begin(), tet.end(), p) != tet.end(); }

int32_t find_root(std::vector<int32_t>& parent, int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

PointSplit split_points(const std::vector<Tet>& tets, const TetFaces& faces, const std::vector<uint8_t>& separated,
                        const std::vector<int32_t>& new_faces, int32_t npoint) {
  PointSplit out;
  out.tet_points = tets;

  // Points on the new faces, ascending.
  std::vector<int32_t> candidates;
  for (int32_t f : new_faces) {
    const auto [t, i] = std::pair{faces.tets[f][0], faces.local[f][0]};
    for (int32_t p : tet_face(tets[t], i)) candidates.push_back(p);
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

  // Tets of each candidate, ascending tet id (CSR).
  std::vector<int32_t> slot(npoint, -1);
  for (size_t k = 0; k < candidates.size(); ++k) slot[candidates[k]] = static_cast<int32_t>(k);
  std::vector<int32_t> start(candidates.size() + 1, 0);
  for (const Tet& tet : tets)
    for (int32_t p : tet)
      if (slot[p] >= 0) ++start[slot[p] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int32_t> incident(start.back()), fill(start.begin(), start.end() - 1);
  for (int32_t t = 0; t < static_cast<int32_t>(tets.size()); ++t)
    for (int32_t p : tets[t])
      if (slot[p] >= 0) incident[fill[slot[p]]++] = t;

  std::vector<int32_t> parent, root_copy;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const int32_t p = candidates[k];
    const int32_t* first = incident.data() + start[k];
    const int32_t n = start[k + 1] - start[k];
    auto local_index = [&](int32_t t) {
      return static_cast<int32_t>(std::lower_bound(first, first + n, t) - first);
    };
    // Union the tets around p across the unseparated faces that contain p.
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
    for (int32_t a = 0; a < n; ++a) {
      const int32_t t = first[a];
      for (int i = 0; i < 4; ++i) {
        if (tets[t][i] == p) continue;  // the face opposite p does not contain it
        const int32_t f = faces.face_of_tet[t][i];
        if (f < 0 || separated[f]) continue;
        const int32_t u = faces.tets[f][0] == t ? faces.tets[f][1] : faces.tets[f][0];
        if (!contains(tets[u], p))
          throw std::logic_error("split_points: tets " + std::to_string(t) + " and " + std::to_string(u) +
                                 " share an unseparated face but not its point " + std::to_string(p));
        const int32_t b = local_index(u);
        const int32_t ra = find_root(parent, a), rb = find_root(parent, b);
        // The root is the lowest local index, i.e. the lowest tet id.
        if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      }
    }
    // Roots in ascending order: the first keeps p, the others get new ids.
    root_copy.assign(n, -1);
    bool split = false;
    for (int32_t a = 0; a < n; ++a) {
      const int32_t r = find_root(parent, a);
      if (root_copy[r] < 0) {
        if (r == 0) {
          root_copy[r] = p;
        } else {
          root_copy[r] = npoint + static_cast<int32_t>(out.appended_origin.size());
          out.appended_origin.push_back(p);
          split = true;
        }
      }
      if (root_copy[r] == p) continue;
      for (int32_t& v : out.tet_points[first[a]])
        if (v == p) v = root_copy[r];
    }
    out.points_split += split ? 1 : 0;
  }
  return out;
}

namespace {

// Boundary faces among `tet_ids` (face i of tet t is open when the tet
// across it no longer shares its vertex ids); calls add(edge) for each of
// their edges that `keep` accepts, and returns those edges sorted.
template <class Keep>
std::vector<Edge> boundary_edges(const std::vector<Tet>& tets, const TetFaces& faces,
                                 const std::vector<int32_t>& tet_ids, Keep keep) {
  auto sorted_face = [&](int32_t t, int i) {
    Tri f = tet_face(tets[t], i);
    std::sort(f.begin(), f.end());
    return f;
  };
  std::vector<Edge> edges;
  for (int32_t t : tet_ids) {
    for (int i = 0; i < 4; ++i) {
      const int32_t f = faces.face_of_tet[t][i];
      const Tri mine = sorted_face(t, i);
      if (f >= 0) {
        const int side = faces.tets[f][0] == t ? 1 : 0;
        if (sorted_face(faces.tets[f][side], faces.local[f][side]) == mine) continue;  // still joined
      }
      for (const Edge e : {Edge{mine[0], mine[1]}, Edge{mine[0], mine[2]}, Edge{mine[1], mine[2]}})
        if (keep(e)) edges.push_back(e);
    }
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

// Edges listed more than twice in sorted `edges`.
std::vector<Edge> listed_more_than_twice(const std::vector<Edge>& edges) {
  std::vector<Edge> bad;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j] == edges[i]) ++j;
    if (j - i > 2) bad.push_back(edges[i]);
    i = j;
  }
  return bad;
}

}  // namespace

std::vector<Edge> nonmanifold_boundary_edges(const std::vector<Tet>& tets, const TetFaces& faces) {
  std::vector<int32_t> all(tets.size());
  std::iota(all.begin(), all.end(), 0);
  return listed_more_than_twice(boundary_edges(tets, faces, all, [](const Edge&) { return true; }));
}

std::vector<Edge> nonmanifold_boundary_edges_near(const PointSplit& split, const GatherLayout& before,
                                                  const TetFaces& faces) {
  const GatherTable& before_tets_of = before.tets;
  const int32_t chunk_size = before.chunk_size;
  const int32_t npoint = static_cast<int32_t>(before_tets_of.count.size());
  auto origin = [&](int32_t p) { return p >= npoint ? split.appended_origin[p - npoint] : p; };
  // Tets (ids never change) around a point before the split: its own and its copies' now.
  std::vector<int32_t> marked;
  std::vector<uint8_t> in(split.tet_points.size(), 0);
  auto add_tets_of = [&](int32_t p) {
    p = origin(p);
    const int32_t first = before_tets_of.chunk_offset[p / chunk_size] + p % chunk_size;
    for (int32_t j = 0; j < before_tets_of.count[p]; ++j) {
      const int32_t t = before_tets_of.item[first + j * chunk_size];
      if (!in[t]) in[t] = 1, marked.push_back(t);
    }
  };
  for (int32_t p : split.appended_origin) add_tets_of(p);
  const std::vector<int32_t> around_split = marked;
  const std::vector<Edge> candidates = boundary_edges(split.tet_points, faces, around_split,
                                                      [](const Edge&) { return true; });
  // Every tet around the candidates' lower ends, so each candidate is
  // counted over all the boundary faces that hold it.
  for (const Edge& e : candidates) add_tets_of(e[0]);
  std::sort(marked.begin(), marked.end());
  return listed_more_than_twice(boundary_edges(split.tet_points, faces, marked, [&](const Edge& e) {
    return std::binary_search(candidates.begin(), candidates.end(), e);
  }));
}

}  // namespace organsim
