#include "core/topology/topology_editor.h"

#include <algorithm>

#include "core/model/model_rebuild.h"

namespace organsim {

void count_spring_changes(const Model& previous, const Model& next, ChangeCounts& counts) {
  // The tissue's spring ends are sorted in every Model version (build_model,
  // rebuild_model); sutures follow them and are counted on their own.
  const auto a = previous.spring_ends.begin(), a_end = a + previous.first_suture();
  const auto b = next.spring_ends.begin(), b_end = b + next.first_suture();
  std::vector<Edge> only;
  std::set_difference(b, b_end, a, a_end, std::back_inserter(only));
  counts.springs_added = static_cast<int32_t>(only.size());
  only.clear();
  std::set_difference(a, a_end, b, b_end, std::back_inserter(only));
  counts.springs_removed = static_cast<int32_t>(only.size());
}

std::vector<int32_t> TopologyEditor::faces_to_keep(const std::vector<Edge>& bad, const PointSplit& split,
                                                   int32_t npoint, const std::vector<int32_t>& fresh) const {
  auto original = [&](int32_t p) { return p >= npoint ? split.appended_origin[p - npoint] : p; };
  auto face_points = [&](int32_t f) {
    // The face's points before this split: the lower tet's vertices mapped back.
    Tri v = tet_face(split.tet_points[faces_.tets[f][0]], faces_.local[f][0]);
    for (int32_t& p : v) p = original(p);
    return v;
  };
  auto has = [](const Tri& v, int32_t p) { return v[0] == p || v[1] == p || v[2] == p; };
  std::vector<int32_t> keep;
  for (const bool both : {true, false}) {
    for (int32_t f : fresh) {
      const Tri v = face_points(f);
      for (const Edge& e : bad) {
        const int32_t a = original(e[0]), b = original(e[1]);
        if (both ? has(v, a) && has(v, b) : has(v, a) || has(v, b)) {
          keep.push_back(f);
          break;
        }
      }
    }
    if (!keep.empty()) return keep;
  }
  return fresh;
}

TopologyEditor::TopologyEditor(const Model& initial)
    : faces_(build_tet_faces(initial.tet_points)), separated_(faces_.nface(), 0) {}

bool TopologyEditor::separate(const Model& current, const std::vector<int32_t>& faces, Model& next,
                              ChangeCounts& counts) {
  std::vector<int32_t> fresh;
  for (int32_t f : faces) {
    if (separated_[f]) continue;
    separated_[f] = 1;
    fresh.push_back(f);
  }
  counts = ChangeCounts{};
  if (fresh.empty()) return false;
  std::sort(fresh.begin(), fresh.end());
  PointSplit split;
  for (;;) {
    split = split_points(current.tet_points, faces_, separated_, fresh, current.npoint());
    const std::vector<Edge> bad = nonmanifold_boundary_edges_near(split, current.layout, faces_);
    if (bad.empty()) break;
    // Opening these faces would leave an edge with more than two boundary
    // faces (a point's tets wrapping around an opened edge): keep joined the
    // new faces at such an edge (or, failing that, at either end) and split
    // again. Reverting every new face restores the previous, manifold state,
    // so this ends. A later tick of the blade may separate them again.
    const std::vector<int32_t> reverted = faces_to_keep(bad, split, current.npoint(), fresh);
    for (int32_t f : reverted) separated_[f] = 0;
    std::vector<int32_t> kept;
    std::set_difference(fresh.begin(), fresh.end(), reverted.begin(), reverted.end(), std::back_inserter(kept));
    fresh = std::move(kept);
    if (fresh.empty()) return false;
  }
  counts.faces_separated = static_cast<int32_t>(fresh.size());
  // Faces separated inside the material with every point still whole (at a
  // blade's tip) change no Model: they open once a later cut frees a point.
  if (split.appended_origin.empty()) return false;
  counts.points_split = split.points_split;
  counts.points_added = static_cast<int32_t>(split.appended_origin.size());
  TopologyChange change;
  change.tet_points = std::move(split.tet_points);
  change.appended_origin = std::move(split.appended_origin);
  next = rebuild_model(current, change);
  count_spring_changes(current, next, counts);
  return true;
}

}  // namespace organsim
