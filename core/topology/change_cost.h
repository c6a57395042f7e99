#pragma once
// What one topology change costs, for `organsim bench`: a local cut (a
// blade 1/5 of the model's width sweeping 1/10 of its height down to the
// middle of its bounding box) timed phase by phase on the CPU backend.
#include <cstdint>

#include "core/model/model.h"

namespace organsim {

struct ChangeCost {
  int32_t faces_separated = 0, points_added = 0;
  double detect_ms = 0;     // blade sweep test over every interior face
  double model_ms = 0;      // point splitting + rebuild_model (masses, springs, gather layout)
  double backend_ms = 0;    // Backend::rebuild of the CPU backend (double)
  double dt_crit_ms = 0;    // estimate_critical_step on the new Model (the run loop's check)
  double total_ms() const { return detect_ms + model_ms + backend_ms + dt_crit_ms; }
};

// Medians over `repeats` cuts, each on a fresh copy of `model`.
ChangeCost measure_change_cost(const Model& model, int repeats = 5);

}  // namespace organsim
