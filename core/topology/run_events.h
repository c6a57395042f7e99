#pragma once
// The scenario's events during a run: which faces the cuts' blades and the
// tear criterion separate over each tick, and the Model version that
// results. The run loop asks before every tick and, when a new version comes
// back, rebuilds the backend from it. Built only for a scenario with events.
#include <nlohmann/json.hpp>

#include <vector>

#include "core/model/model.h"
#include "core/scenario/events.h"
#include "core/stability/critical_step.h"
#include "core/stability/step_after_change.h"
#include "core/topology/tear.h"
#include "core/topology/topology_editor.h"

namespace organsim {

class TopologyEvents {
 public:
  TopologyEvents(const EventsDef& events, const Model& initial);

  // Whether anything happens over the tick [t0, t1] (then positions are needed).
  bool active(double t0, double t1) const;

  // The changes over the tick [t0, t1] at positions x (internal numbering of
  // `current`): blades sweep from their pose at t0 to their pose at t1, the
  // tear criterion looks at x. Returns true when `next` holds a new Model
  // version (the backend must be rebuilt from it before the tick).
  bool before_tick(double t0, double t1, const Model& current, const std::vector<Vec3>& x, Model& next);

  // The guaranteed-stable step of `next`, the version just made from
  // `previous` (core/stability/step_after_change.h: only the rows the change
  // touched are recomputed).
  double guaranteed_step(const Model& previous, const Model& next, const CriticalStepOptions& options);

  // Records the change just made (time, kinds, counts, the backend's rebuild
  // time, the guaranteed step and, when the run needed it, the new dt_crit
  // from the full estimate, and how long the check took) and carries the
  // tear counters over.
  void changed(const Model& previous, const Model& next, double rebuild_seconds, double dt_crit_guaranteed,
               const StabilityReport* full, double check_seconds);

  // meta.events of the force log: one entry per change.
  const nlohmann::json& log() const { return log_; }
  const TopologyEditor& editor() const { return editor_; }

 private:
  const EventsDef& events_;
  TopologyEditor editor_;
  std::optional<TearDetector> tear_;
  ChangeStepCheck step_check_;
  nlohmann::json log_ = nlohmann::json::array();
  nlohmann::json pending_;  // the entry of the change before_tick just made
  int32_t unopened_faces_ = 0;  // separated with no point split yet (at a blade's tip)
};

}  // namespace organsim
