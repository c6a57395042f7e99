#pragma once
// Point orderings for the gather layout.
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// Reverse Cuthill-McKee order of the graph given by `edges` over npoint
// nodes: order[k] = node placed at position k. Neighbouring points end up
// close in memory, which matters more than anything for threaded gathers
// (docs/architecture.md, "Numbering and the gather layout"). Each connected
// component starts from a pseudo-peripheral node; ties break by node id, so
// the order is deterministic.
std::vector<int32_t> reverse_cuthill_mckee(int32_t npoint, const std::vector<Edge>& edges);

// Stable sort of `order` by decreasing valence within consecutive windows of
// `window` entries (the sigma of SELL-C-sigma): the paper's valence sort
// without destroying locality. window >= order.size() is the paper's global sort.
void sort_by_valence_in_windows(std::vector<int32_t>& order, const std::vector<int32_t>& valence,
                                int32_t window);

}  // namespace organsim
