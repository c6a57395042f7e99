#include "core/model/layout_build.h"

#include <algorithm>
#include <numeric>

#include "core/util/error.h"

namespace organsim {

namespace {

// Per-point item lists in one flat array (CSR): the items of point p are
// item[start[p]] .. item[start[p + 1] - 1], in the order their slots take.
struct ItemsOfPoint {
  std::vector<int32_t> start;  // (npoint + 1)
  std::vector<int32_t> item;
};

// Items of each point by counting: points_of(i, add) calls add(p) for each
// point that item i belongs to; each point's items come in ascending id.
template <class PointsOf>
ItemsOfPoint items_of_points(int32_t npoint, int32_t nitem, PointsOf points_of) {
  ItemsOfPoint out;
  out.start.assign(static_cast<size_t>(npoint) + 1, 0);
  for (int32_t i = 0; i < nitem; ++i) points_of(i, [&](int32_t p) { ++out.start[p + 1]; });
  std::partial_sum(out.start.begin(), out.start.end(), out.start.begin());
  out.item.resize(out.start.back());
  std::vector<int32_t> next(out.start.begin(), out.start.end() - 1);
  for (int32_t i = 0; i < nitem; ++i) points_of(i, [&](int32_t p) { out.item[next[p]++] = i; });
  return out;
}

// Calls f(entry, p, j) for slot j of every point p that holds an item.
template <class F>
void for_each_entry(const GatherTable& table, int32_t chunk_size, F f) {
  for (int32_t p = 0; p < static_cast<int32_t>(table.count.size()); ++p) {
    const int32_t first = table.chunk_offset[p / chunk_size] + p % chunk_size;
    for (int32_t j = 0; j < table.count[p]; ++j) f(first + j * chunk_size, p, j);
  }
}

// Lays out per-point item lists slot-major within chunks of C points.
GatherTable make_table(const ItemsOfPoint& items, int32_t chunk_size) {
  const int32_t npoint = static_cast<int32_t>(items.start.size()) - 1;
  const int32_t nchunk = (npoint + chunk_size - 1) / chunk_size;
  GatherTable table;
  table.count.resize(npoint);
  table.chunk_width.resize(nchunk);
  table.chunk_offset.resize(nchunk + 1);
  table.chunk_offset[0] = 0;
  for (int32_t c = 0; c < nchunk; ++c) {
    int32_t width = 0;
    for (int32_t p = c * chunk_size; p < std::min(npoint, (c + 1) * chunk_size); ++p) {
      table.count[p] = items.start[p + 1] - items.start[p];
      width = std::max(width, table.count[p]);
    }
    table.chunk_width[c] = width;
    table.chunk_offset[c + 1] = table.chunk_offset[c] + width * chunk_size;
  }
  table.item.assign(table.chunk_offset[nchunk], -1);
  for_each_entry(table, chunk_size,
                 [&](int32_t entry, int32_t p, int32_t j) { table.item[entry] = items.item[items.start[p] + j]; });
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

  // Springs of each point, by increasing other end so neighbour reads walk
  // forward. In spring id order they already are when the springs are sorted
  // by their ends (tet edges are); the sort is for any that are not.
  const auto& ends = model.spring_ends;
  ItemsOfPoint springs_of = items_of_points(npoint, model.nspring(), [&](int32_t s, auto add) {
    add(ends[s][0]);
    add(ends[s][1]);
  });
  for (int32_t p = 0; p < npoint; ++p) {
    // The other end is the sum of the ends minus p: comparing sums compares other ends.
    const auto by_other = [&](int32_t a, int32_t b) { return ends[a][0] + ends[a][1] < ends[b][0] + ends[b][1]; };
    const auto first = springs_of.item.begin() + springs_of.start[p];
    const auto last = springs_of.item.begin() + springs_of.start[p + 1];
    if (!std::is_sorted(first, last, by_other)) std::sort(first, last, by_other);
  }
  layout.springs = make_table(springs_of, chunk_size);
  layout.spring_other.assign(layout.springs.item.size(), -1);
  for_each_entry(layout.springs, chunk_size, [&](int32_t e, int32_t p, int32_t) {
    const int32_t s = layout.springs.item[e];
    layout.spring_other[e] = ends[s][0] + ends[s][1] - p;
  });

  // Tets of each point; the other three vertices in an order that keeps the
  // tet's orientation with p first: (p0,p1,p2,p3), (p1,p0,p3,p2),
  // (p2,p0,p1,p3), (p3,p0,p2,p1) are all even permutations.
  static constexpr int kOthers[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  const ItemsOfPoint tets_of = items_of_points(npoint, model.ntet(), [&](int32_t t, auto add) {
    for (int32_t v : model.tet_points[t]) add(v);
  });
  layout.tets = make_table(tets_of, chunk_size);
  layout.tet_others.assign(layout.tets.item.size(), {-1, -1, -1});
  for_each_entry(layout.tets, chunk_size, [&](int32_t e, int32_t p, int32_t) {
    const Tet& tet = model.tet_points[layout.tets.item[e]];
    const int corner = static_cast<int>(std::find(tet.begin(), tet.end(), p) - tet.begin());
    for (int k = 0; k < 3; ++k) layout.tet_others[e][k] = tet[kOthers[corner][k]];
  });
  return layout;
}

}  // namespace organsim
