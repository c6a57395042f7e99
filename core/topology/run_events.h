#pragma once
// The scenario's events during a run: which faces the cuts' blades and the
// tear criterion separate over each tick, which sutures are tied, and the
// Model version that results. The run loop asks before every tick and, when a new version comes
// back, rebuilds the backend from it. Built only for a scenario with events.
#include <nlohmann/json.hpp>

#include <vector>

#include "core/model/model.h"
#include "core/scenario/events.h"
#include "core/stability/critical_step.h"
#include "core/stability/step_after_change.h"
#include "core/topology/suture_select.h"
#include "core/topology/tear.h"
#include "core/topology/topology_editor.h"

namespace organsim {

// The largest suture tension k max(0, L - r(t)) (the damper left out) at
// positions x and time t, N; 0 without sutures.
double suture_tension_max(const Model& model, const std::vector<Vec3>& x, double t);

// meta.sutures of the force log at the end of a run: how many, their longest
// rest length when tied, their longest length and largest tension now (at
// positions x and time t), and `tension_peak`, the largest tension the run
// saw at the end of any tick.
nlohmann::json suture_summary(const Model& model, const std::vector<Vec3>& x, double t, double tension_peak);

// Whether the change over a tick may be built off the tick's path
// (core/run/change_worker.h): only when all that happens then is cuts
// marked for it (CutEvent::applied_at later than the tick, or when_ready).
// `at`: the time of the tick that swaps it in (the earliest applied_at);
// absent: the first tick after it is built.
struct OffPathPlan {
  bool off = false;
  std::optional<double> at;
};

// How long the parts of a change that follow the new Model took, s (meta.events).
struct ChangeTimes {
  double rebuild_seconds = 0;  // the backend's part on the tick's path: adopt(), or the whole rebuild()
  std::optional<double> prepare_seconds;  // its part off the tick's path (prepare() on the worker), if any
  double check_seconds = 0;               // the dt check on the tick's path
  std::optional<double> check_prepare_seconds;  // the dt check off the tick's path (on the worker), if any
};

class TopologyEvents {
 public:
  TopologyEvents(const EventsDef& events, const Model& initial);

  // A cut added during the run (organsim serve's client cut), from now on
  // like the scenario's cuts; its name must be new.
  void add_cut(CutEvent cut);

  // Whether anything happens over the tick [t0, t1] (then positions are needed).
  bool active(double t0, double t1) const;
  // For an active tick: whether its change may be built off the tick's path
  // (dt: the time step, for rounding applied_at).
  OffPathPlan off_path(double t0, double t1, double dt) const;

  // The changes over the tick [t0, t1] at positions x (internal numbering of
  // `current`): blades sweep from their pose at t0 to their pose at t1, the
  // tear criterion looks at x, sutures due are tied at t0 (after this tick's
  // cuts, on the Model they made). Returns true when `next` holds a new Model
  // version (the backend must be rebuilt from it before the tick).
  bool before_tick(double t0, double t1, const Model& current, const std::vector<Vec3>& x, Model& next);

  // The guaranteed-stable step of `next`, the version just made from
  // `previous` (core/stability/step_after_change.h: only the rows the change
  // touched are recomputed).
  double guaranteed_step(const Model& previous, const Model& next, const CriticalStepOptions& options);

  // Records the change just made (time, kinds, counts incl. sutures, how
  // long the backend's rebuild and the check took, the guaranteed step and,
  // when the run needed it, the new dt_crit from the full estimate) and
  // carries the tear counters over.
  // `applied_t`: the start of the tick that swapped it in, when that was
  // later than the tick that made it (off the tick's path).
  void changed(const Model& previous, const Model& next, const ChangeTimes& times, double dt_crit_guaranteed,
               const StabilityReport* full, std::optional<double> applied_t = std::nullopt);

  // meta.events of the force log: one entry per change.
  const nlohmann::json& log() const { return log_; }
  const TopologyEditor& editor() const { return editor_; }

 private:
  bool suture_due(size_t i, double t0, double t1) const;
  // Cuts and tear: true when `next` holds the split Model.
  bool separate(double t0, double t1, const Model& current, const std::vector<Vec3>& x, Model& next,
                nlohmann::json& sources, ChangeCounts& counts);
  // Sutures due: true when `next` holds `base` with them added (`base` may be `next`).
  bool tie_sutures_due(double t0, double t1, const Model& base, const std::vector<Vec3>& x, Model& next,
                       nlohmann::json& sources);

  EventsDef events_;  // the scenario's, and the cuts added during the run
  TopologyEditor editor_;
  std::vector<CutRecord> cut_records_;  // per cut: the faces its blade separated
  std::vector<uint8_t> tied_;           // per suture event: done
  std::vector<Vec3> x_base_;            // positions extended to the points a cut appended this tick
  std::optional<TearDetector> tear_;
  ChangeStepCheck step_check_;
  nlohmann::json log_ = nlohmann::json::array();
  nlohmann::json pending_;  // the entry of the change before_tick just made
  int32_t unopened_faces_ = 0;  // separated with no point split yet (at a blade's tip)
};

}  // namespace organsim
