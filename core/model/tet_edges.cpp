#include "core/model/tet_edges.h"

#include <algorithm>
#include <numeric>
#include <utility>

namespace organsim {

TetEdges tet_edges(const std::vector<Tet>& tets, int32_t npoint, const std::vector<double>& tet_volume) {
  const bool with_volume = !tet_volume.empty();
  // Tets of each point, ascending tet id (CSR).
  std::vector<int32_t> start(static_cast<size_t>(npoint) + 1, 0);
  for (const Tet& tet : tets)
    for (int32_t p : tet) ++start[p + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int32_t> incident(start.back()), fill(start.begin(), start.end() - 1);
  for (int32_t t = 0; t < static_cast<int32_t>(tets.size()); ++t)
    for (int32_t p : tets[t]) incident[fill[p]++] = t;

  TetEdges out;
  out.ends.reserve(tets.size() * 2);  // a tet mesh has about 1.2 edges per tet
  if (with_volume) out.volume.reserve(out.ends.capacity());
  std::vector<int32_t> slot(npoint, -1);      // position of a higher end in `higher`, -1 if absent
  std::vector<std::pair<int32_t, double>> higher;  // higher ends of p's edges and their volumes
  for (int32_t p = 0; p < npoint; ++p) {
    higher.clear();
    for (int32_t k = start[p]; k < start[p + 1]; ++k) {
      const int32_t t = incident[k];
      for (int32_t q : tets[t]) {
        if (q <= p) continue;
        if (slot[q] < 0) {
          slot[q] = static_cast<int32_t>(higher.size());
          higher.push_back({q, 0.0});
        }
        if (with_volume) higher[slot[q]].second += tet_volume[t];
      }
    }
    std::sort(higher.begin(), higher.end());
    for (const auto& [q, volume] : higher) {
      slot[q] = -1;
      out.ends.push_back({p, q});
      if (with_volume) out.volume.push_back(volume);
    }
  }
  return out;
}

}  // namespace organsim
