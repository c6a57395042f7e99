#pragma once
// A topology change off the tick's path (docs/topology.md, "Off the tick's
// path"): the next Model version, its guaranteed-stable step and the
// backend's tables for it (Backend::prepare), and the full dt_crit estimate
// when the step is above the guaranteed one, are made on a worker thread
// from the positions at the start of the tick that asked for it, while the
// run loop steps the previous version; the loop swaps it in (Backend::adopt)
// later, at a tick the change names (applied_at, a replay) or at the first
// tick after the worker is done (a live client's cut). While it is busy the
// loop touches nothing of the TopologyEvents but their read-only active().
#include <future>
#include <memory>
#include <optional>
#include <vector>

#include "core/model/model.h"
#include "core/sim/backend.h"
#include "core/stability/critical_step.h"
#include "core/topology/run_events.h"

namespace organsim {

class ChangeWorker {
 public:
  struct Built {
    std::unique_ptr<Model> next;  // null when the change separated nothing
    double guaranteed = 0;        // the next version's guaranteed-stable step, s
    // The power iteration's estimate for `next`, made when dt > guaranteed
    // (at 28k points it takes over a second: never on the tick's path).
    std::optional<StabilityReport> full;
    double check_seconds = 0;                 // how long the guaranteed step and `full` took
    std::unique_ptr<PreparedModel> prepared;  // `next` packed by the backend's prepare()
    double prepare_seconds = 0;               // how long prepare() took on the worker
  };

  ~ChangeWorker() { abandon(); }

  // Starts the change over the tick [t0, t1] of `events` on `current` at
  // positions x (as TopologyEvents::before_tick), for a run at step dt;
  // `when` as returned by TopologyEvents::off_path. `current`, `events`,
  // `tool` and `backend` must outlive it; the worker calls only
  // backend.prepare().
  void start(TopologyEvents& events, const Model& current, std::vector<Vec3> x, double t0, double t1, double dt,
             const ToolSpec* tool, const Backend& backend, const OffPathPlan& when);
  bool busy() const { return future_.valid(); }
  // Whether the tick starting at t0 (time step dt, for rounding) swaps it in.
  bool due(double t0, double dt) const;
  // Waits for it (rethrowing the worker's error) and hands it over.
  Built take();
  // Waits for it and drops it (the run ends).
  void abandon();

 private:
  std::future<Built> future_;
  std::optional<double> at_;  // absent: as soon as it is ready
};

}  // namespace organsim
