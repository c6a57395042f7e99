#include "core/model/layout_build.h"

#include <algorithm>

#include "core/util/error.h"

namespace organsim {

namespace {

// Lays out per-point item lists slot-major within chunks of C points.
// `items_of[p]` must already be in the order the slots should take.
GatherTable make_table(const std::vector<std::vector<int32_t>>& items_of, int32_t chunk_size) {
  const int32_t npoint = static_cast<int32_t>(items_of.size());
  const int32_t nchunk = (npoint + chunk_size - 1) / chunk_size;
  GatherTable table;
  table.count.resize(npoint);
  table.chunk_width.resize(nchunk);
  table.chunk_offset.resize(nchunk + 1);
  table.chunk_offset[0] = 0;
  for (int32_t c = 0; c < nchunk; ++c) {
    int32_t width = 0;
    for (int32_t p = c * chunk_size; p < std::min(npoint, (c + 1) * chunk_size); ++p) {
      table.count[p] = static_cast<int32_t>(items_of[p].size());
      width = std::max(width, table.count[p]);
    }
    table.chunk_width[c] = width;
    table.chunk_offset[c + 1] = table.chunk_offset[c] + width * chunk_size;
  }
  table.item.assign(table.chunk_offset[nchunk], -1);
  for (int32_t p = 0; p < npoint; ++p) {
    const int32_t c = p / chunk_size, lane = p % chunk_size;
    for (int32_t j = 0; j < table.count[p]; ++j)
      table.item[table.chunk_offset[c] + j * chunk_size + lane] = items_of[p][j];
  }
  return table;
}

}  // namespace

GatherLayout build_gather_layout(const Model& model, int32_t chunk_size, int32_t sort_window) {
  if (chunk_size < 1) throw Error(ErrorKind::Scenario, "layout chunk size must be >= 1");
  const int32_t npoint = model.npoint();
  GatherLayout layout;
  layout.chunk_size = chunk_size;
  layout.sort_window = sort_window;
  layout.nchunk = (npoint + chunk_size - 1) / chunk_size;

  // Springs of each point, by increasing other end so neighbour reads walk forward.
  std::vector<std::vector<int32_t>> springs_of(npoint);
  for (int32_t s = 0; s < model.nspring(); ++s) {
    springs_of[model.spring_ends[s][0]].push_back(s);
    springs_of[model.spring_ends[s][1]].push_back(s);
  }
  for (int32_t p = 0; p < npoint; ++p) {
    auto other = [&](int32_t s) { return model.spring_ends[s][0] + model.spring_ends[s][1] - p; };
    std::sort(springs_of[p].begin(), springs_of[p].end(),
              [&](int32_t a, int32_t b) { return other(a) < other(b); });
  }
  layout.springs = make_table(springs_of, chunk_size);
  layout.spring_other.assign(layout.springs.item.size(), -1);
  for (int32_t e = 0; e < static_cast<int32_t>(layout.springs.item.size()); ++e) {
    const int32_t s = layout.springs.item[e];
    if (s < 0) continue;
    const int32_t p = point_of_entry(layout.springs, chunk_size, e);
    layout.spring_other[e] = model.spring_ends[s][0] + model.spring_ends[s][1] - p;
  }

  // Tets of each point; the other three vertices in an order that keeps the
  // tet's orientation with p first: (p0,p1,p2,p3), (p1,p0,p3,p2),
  // (p2,p0,p1,p3), (p3,p0,p2,p1) are all even permutations.
  static constexpr int kOthers[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  std::vector<std::vector<int32_t>> tets_of(npoint);
  for (int32_t t = 0; t < model.ntet(); ++t)
    for (int32_t v : model.tet_points[t]) tets_of[v].push_back(t);
  layout.tets = make_table(tets_of, chunk_size);
  layout.tet_others.assign(layout.tets.item.size(), {-1, -1, -1});
  for (int32_t e = 0; e < static_cast<int32_t>(layout.tets.item.size()); ++e) {
    const int32_t t = layout.tets.item[e];
    if (t < 0) continue;
    const int32_t p = point_of_entry(layout.tets, chunk_size, e);
    const Tet& tet = model.tet_points[t];
    const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), p) - tet.begin());
    for (int k = 0; k < 3; ++k) layout.tet_others[e][k] = tet[kOthers[corner][k]];
  }
  return layout;
}

}  // namespace organsim
