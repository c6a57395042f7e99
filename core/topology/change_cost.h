#pragma once
// What one topology change costs, for `organsim bench`: a local cut timed
// phase by phase on the CPU backend. The blade is sized by the mesh, not by
// the model's extent, so every mesh size cuts a comparable patch of about
// the same number of faces: an edge 4 h long (h = median spring rest length)
// centred on the tet centroid nearest the bounding box's centre, in the
// plane x = const through it, sweeping down 3 h across it.
#include <cstdint>

#include "core/model/model.h"

namespace organsim {

struct ChangeCost {
  int32_t faces_separated = 0, points_added = 0;
  double detect_ms = 0;      // blade sweep test over every interior face
  double model_ms = 0;       // point splitting + rebuild_model (masses, springs, gather layout)
  double backend_ms = 0;     // Backend::rebuild of the CPU backend (double)
  double dt_check_ms = 0;    // the run's check of dt: Gershgorin rows of the changed points, guaranteed step
  double dt_crit_ms = 0;     // estimate_critical_step on the new Model: the run needs it only when dt is above
                             // the guaranteed step, so it is not in total_ms
  double guaranteed_over_dt_crit = 0;  // the guaranteed step / dt_crit after the change
  double total_ms() const { return detect_ms + model_ms + backend_ms + dt_check_ms; }
};

// Medians over `repeats` cuts, each on a fresh copy of `model`.
ChangeCost measure_change_cost(const Model& model, int repeats = 5);

}  // namespace organsim
