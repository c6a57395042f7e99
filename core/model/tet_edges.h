#pragma once
// The unique edges of a tet mesh, each with the summed rest volume of the
// tets that contain it: the springs of build_model and rebuild_model.
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

struct TetEdges {
  std::vector<Edge> ends;      // unique edges, ascending, ends[0] < ends[1] (nedge x 2)
  std::vector<double> volume;  // summed volume of the tets containing each edge, m^3 (nedge); empty if none given
};

// Edges of `tets` (vertex ids < npoint). With `tet_volume` (ntet), each
// edge's volume is summed over its tets in ascending tet id, the order a
// loop over the tets takes, so the sums are reproducible bit for bit. Linear
// in the number of tets: each point collects the higher ends of its edges
// from its own tets, so no global sort of the ~6 ntet edge copies.
TetEdges tet_edges(const std::vector<Tet>& tets, int32_t npoint, const std::vector<double>& tet_volume = {});

}  // namespace organsim
