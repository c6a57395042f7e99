#include "core/stability/step_after_change.h"

#include <stdexcept>
#include <string>

namespace organsim {

ChangeStepCheck::ChangeStepCheck(const Model& initial) : rows_(gershgorin_rows(initial)) {}

void ChangeStepCheck::update(const Model& previous, const Model& next) {
  const int32_t old_n = previous.npoint(), n = next.npoint();
  if (static_cast<int32_t>(rows_.all.size()) != old_n || n < old_n)
    throw std::logic_error("ChangeStepCheck::update: rows for " + std::to_string(rows_.all.size()) +
                           " points, previous version has " + std::to_string(old_n) + ", next " +
                           std::to_string(n));
  rows_.all.resize(n, 0.0);
  rows_.damped.resize(n, 0.0);
  // A copy takes its origin's scale. The points that were there keep theirs,
  // so every row not recomputed still has its elements' scales: all rows are
  // bounds with one positive scale, which is all the proof needs.
  rows_.scale.resize(n, 0.0);
  for (int32_t p = old_n; p < n; ++p) rows_.scale[p] = rows_.scale[next.origin[p]] > 0 ? rows_.scale[next.origin[p]] : 1.0;
  touched_.assign(n, 0);
  std::vector<int32_t> changed;
  for (int32_t p = old_n; p < n; ++p)
    for (int32_t q : {p, next.origin[p]})
      if (!touched_[q]) touched_[q] = 1, changed.push_back(q);
  // The ends of sutures tied by this change (sutures are append-only).
  for (int32_t s = previous.nsuture(); s < next.nsuture(); ++s)
    for (int32_t q : next.sutures[s].ends)
      if (!touched_[q]) touched_[q] = 1, changed.push_back(q);
  // Their spring neighbours: a neighbour's spring to a split point may now be
  // two springs (one per side) whose stiffnesses sum to the old one. With the
  // nodal volume term or smoothed shear patches also the next ring: a row
  // sums over the patches of its neighbours, whose own tets reach the split
  // points.
  const GatherLayout& layout = next.layout;
  const int32_t c = layout.chunk_size;
  size_t ring_begin = 0;
  for (int ring = 0; ring < (next.has_nodal_volume() || next.has_smoothed_shear() ? 2 : 1); ++ring) {
    const size_t ring_end = changed.size();
    for (size_t k = ring_begin; k < ring_end; ++k) {
      const int32_t p = changed[k];
      const int32_t first = layout.springs.chunk_offset[p / c] + p % c;
      for (int32_t j = 0; j < layout.springs.count[p]; ++j) {
        const int32_t q = layout.spring_other[first + j * c];
        if (!touched_[q]) touched_[q] = 1, changed.push_back(q);
      }
    }
    ring_begin = ring_end;
  }
  compute_gershgorin_rows(next, changed, rows_);
}

}  // namespace organsim
