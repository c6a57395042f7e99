#pragma once
// A run whose tool is driven from outside the scenario (`organsim serve`,
// core/live): the run loop asks the driver for the tool centre at the end of
// each tick instead of reading the scenario's keyframes, lets it end the run
// early, may ask for a cut over a tick, and adds the driver's record to the
// force log's meta. Everything else (backend step, grasp, events, observers,
// the log) is the ordinary run.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>

#include "core/scenario/events.h"
#include "core/util/vec.h"

namespace organsim {

class ToolDriver {
 public:
  virtual ~ToolDriver() = default;
  // The tool centre at the end of tick `tick` (which ends at simulated time
  // `t_end`, s), m; called once per tick, in order, before the step. nullopt
  // ends the run before this tick: it then completes with the ticks done.
  virtual std::optional<Vec3> tool_at_end_of(int64_t tick, double t_end) = 0;
  // A cut over the tick just asked for (its blade keyframes span that tick),
  // or nullopt; called right after tool_at_end_of. The run applies it as a
  // scripted cut from then on, so a scenario holding the same cut replays it.
  virtual std::optional<CutEvent> cut_for_tick() { return std::nullopt; }
  // The driver's last cut (built off the tick's path when it is marked
  // when_ready) was swapped in, or found to change nothing, at the tick
  // starting at `t0`: the driver's record of it gets applied_at = t0 so that
  // its replay swaps it in at the same tick.
  virtual void cut_applied(double /*t0*/) {}
  // Added to the force log's meta.extra when the log is written (also when
  // the run failed).
  virtual void add_meta(nlohmann::json& extra) const = 0;
};

}  // namespace organsim
