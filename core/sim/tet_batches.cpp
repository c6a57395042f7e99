#include "core/sim/tet_batches.h"

#include <algorithm>
#include <array>

namespace organsim {

namespace {

// Deals `run` (tets in order of their lowest vertex) out to batches of
// `lanes` so that no two tets of a batch share a vertex and each batch holds
// tets from one small part of the mesh: each tet goes to the oldest open
// batch that holds none of its vertices, and at most kOpenBatches are open
// at once (the oldest is closed, padded, when another must open). Sharing
// no vertex lets a kernel load all of a batch's forces before storing any;
// locality keeps a batch's records and forces in cache (lanes from distant
// parts of the mesh, the first version, made the tet pass memory bound at
// Bunny7 size). Returns the tet of each lane, -1 for padding.
template <size_t N>
std::vector<int32_t> batch_tets(const std::vector<int32_t>& run, const std::vector<std::array<int32_t, N>>& tets,
                                int32_t npoint, int32_t lanes) {
  constexpr int32_t kOpenBatches = 32;  // one bit each in a point's mask
  std::vector<int32_t> lane_tet, fill;  // fill: lanes used per batch
  // Bit b % kOpenBatches is set for the open batches b holding the point.
  std::vector<uint32_t> in_open(static_cast<size_t>(npoint), 0);
  int32_t oldest = 0;  // batches before it are closed
  auto close_oldest = [&] {
    for (int32_t l = 0; l < fill[oldest]; ++l)
      for (const int32_t v : tets[lane_tet[static_cast<size_t>(oldest) * lanes + l]])
        in_open[v] &= ~(1u << (oldest % kOpenBatches));
    ++oldest;
  };
  for (const int32_t t : run) {
    uint32_t taken = 0;
    for (const int32_t v : tets[t]) taken |= in_open[v];
    int32_t b = oldest;
    const int32_t nbatch = static_cast<int32_t>(fill.size());
    while (b < nbatch && (fill[b] == lanes || (taken >> (b % kOpenBatches) & 1))) ++b;
    if (b == nbatch) {
      if (nbatch - oldest == kOpenBatches) close_oldest();
      fill.push_back(0);
      lane_tet.resize(lane_tet.size() + lanes, -1);
    }
    lane_tet[static_cast<size_t>(b) * lanes + fill[b]++] = t;
    for (const int32_t v : tets[t]) in_open[v] |= 1u << (b % kOpenBatches);
    while (oldest < static_cast<int32_t>(fill.size()) && fill[oldest] == lanes) close_oldest();
  }
  return lane_tet;
}

// `order` (elements by lowest vertex) cut into `slices` equal runs, each
// dealt out to batches by batch_tets().
template <size_t N>
TetBatches batch_in_slices(const std::vector<int32_t>& order, const std::vector<std::array<int32_t, N>>& elements,
                           int32_t npoint, int32_t lanes, int32_t slices) {
  const int32_t nt = static_cast<int32_t>(order.size());
  TetBatches out;
  out.slice_begin.push_back(0);
  for (int32_t sl = 0; sl < slices; ++sl) {
    const int32_t first = (nt * sl) / slices, last = (nt * (sl + 1)) / slices;
    const std::vector<int32_t> run(order.begin() + first, order.begin() + last);
    const std::vector<int32_t> slice = batch_tets(run, elements, npoint, lanes);
    out.lane_tet.insert(out.lane_tet.end(), slice.begin(), slice.end());
    out.slice_begin.push_back(static_cast<int32_t>(out.lane_tet.size() / lanes));
  }
  return out;
}

}  // namespace

std::vector<int32_t> tets_by_lowest_vertex(const Model& model) {
  std::vector<int32_t> order(model.ntet());
  for (int32_t t = 0; t < model.ntet(); ++t) order[t] = t;
  auto lowest = [&](int32_t t) { return *std::min_element(model.tet_points[t].begin(), model.tet_points[t].end()); };
  std::stable_sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return lowest(a) < lowest(b); });
  return order;
}

TetBatches batch_model_tets(const Model& model, int32_t lanes, int32_t slices) {
  const std::vector<int32_t> order =
      model.has_volume() || model.has_shear_element() ? tets_by_lowest_vertex(model) : std::vector<int32_t>{};
  return batch_in_slices(order, model.tet_points, model.npoint(), lanes, slices);
}

TetBatches batch_tet_pairs(const std::vector<TetPair>& pairs, int32_t npoint, int32_t lanes, int32_t slices) {
  std::vector<std::array<int32_t, 5>> points(pairs.size());
  std::vector<int32_t> order(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    points[i] = pairs[i].v;
    order[i] = static_cast<int32_t>(i);
  }
  return batch_in_slices(order, points, npoint, lanes, slices);
}

}  // namespace organsim
