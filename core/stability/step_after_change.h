#pragma once
// Is the run's dt still stable after a topology change? The full answer,
// estimate_critical_step, runs a power iteration over the whole model (about
// 100 ms at 7.7k points). A split only touches the rows of M^-1 K at the
// split points, their copies and their neighbours, so the Gershgorin rows
// (core/stability/gershgorin.h) are kept from version to version and only
// those rows recomputed: the guaranteed step then costs O(changed points)
// plus one pass over the points for the maximum. When dt is below it, dt is
// stable and the full estimate would accept it too (its dt_crit is never
// below the guaranteed step); only otherwise does the run need the power
// iteration.
#include <cstdint>

#include "core/model/model.h"
#include "core/stability/critical_step.h"
#include "core/stability/gershgorin.h"

namespace organsim {

class ChangeStepCheck {
 public:
  explicit ChangeStepCheck(const Model& initial);

  // Follows `next`, made from `previous` by appending copies (ids kept) and
  // sutures: recomputes the rows of the copies, their origins, the new
  // sutures' ends and every spring neighbour of those (two rings with node
  // patches). A copy takes its origin's scale; every other row is computed
  // from the same springs (same stiffness, same order), tets, masses and
  // scales as before, so the rows equal
  // gershgorin_rows_with_scale(next, rows().scale) exactly.
  void update(const Model& previous, const Model& next);

  const GershgorinRows& rows() const { return rows_; }

  // guaranteed_critical_step of the current version.
  double guaranteed_step(const Model& current, const CriticalStepOptions& options) const {
    return guaranteed_critical_step(current, rows_, options);
  }

 private:
  GershgorinRows rows_;
  std::vector<uint8_t> touched_;  // scratch (npoint)
};

}  // namespace organsim
