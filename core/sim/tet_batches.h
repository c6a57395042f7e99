#pragma once
// How the simd kernel groups tets: each tet evaluated once, `lanes` per
// batch (one register), the lanes of a batch sharing no vertex, and the
// batches cut into fixed slices that each add into their own force array.
#include <cstdint>
#include <vector>

#include "core/model/model.h"
#include "core/sim/tet_pairs.h"

namespace organsim {

struct TetBatches {
  std::vector<int32_t> lane_tet;     // tet of each batch lane, -1 for padding (nbatch x lanes)
  std::vector<int32_t> slice_begin;  // first batch of each slice (nslice + 1)
};

// The model's tets in order of their lowest vertex (stable): the batches'
// locality order.
std::vector<int32_t> tets_by_lowest_vertex(const Model& model);

// The model's tets sorted by lowest vertex, cut into `slices` equal runs,
// each run dealt out to batches of `lanes` by batch_tets() (tet_batches.cpp).
TetBatches batch_model_tets(const Model& model, int32_t lanes, int32_t slices);

// The same for tet pairs (in their order, by lowest vertex), no two pairs
// of a batch sharing a point; lane_tet holds pair indices.
TetBatches batch_tet_pairs(const std::vector<TetPair>& pairs, int32_t npoint, int32_t lanes, int32_t slices);

}  // namespace organsim
