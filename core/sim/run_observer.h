#pragma once
// Things that watch a run tick by tick (frame recorder, stability checks, ...)
// without the run loop knowing what they are. Observers that need positions
// ask the backend for them only on the ticks they want, so a scene without
// frames never reads positions back.
#include "core/sim/backend.h"

namespace organsim {

struct TickInfo {
  int64_t tick = 0;       // 0-based tick index
  double t = 0;           // simulated time at the end of the tick, s
  Vec3 tool_center{0, 0, 0};  // at the end of the tick, m
  Quat tool_orientation = Quat::Identity();  // at the end of the tick
  Vec3 tool_from{0, 0, 0};    // at its start, m
  bool tool_active = false;
  Reaction reaction;      // as returned by Backend::tick (latency applies)
  // A pulling tool: dF/dc of its attachment springs while it holds points
  // (attachment_stiffness, N/m), zero otherwise.
  Eigen::Matrix3d held_stiffness = Eigen::Matrix3d::Zero();
};

class RunObserver {
 public:
  virtual ~RunObserver() = default;
  virtual void on_start(const Model& /*model*/, Backend& /*backend*/) {}
  virtual void on_tick(const Model& model, Backend& backend, const TickInfo& info) = 0;
  // A topology change (cut, tear) replaced the Model between two ticks; the
  // backend is already rebuilt from `next`, which keeps the old point ids and
  // appends copies (next.origin). Later calls pass `next`; the old Model is
  // freed after this returns, so drop any reference to it here.
  virtual void on_topology_changed(const Model& /*next*/, Backend& /*backend*/) {}
  // Called once after the last tick, or after an error stopped the run.
  virtual void on_finish(const Model& /*model*/, Backend& /*backend*/) {}
};

}  // namespace organsim
