#pragma once
// The run loop: steps a backend through a scenario's timeline one haptic tick
// at a time, drives the tool (keyframes, grasp, release), records the tool
// reaction per tick and writes OUTDIR/forces.json. Frame recording and checks
// come in as RunObservers from the caller, so this loop knows nothing of them.
#include <filesystem>
#include <string>
#include <vector>

#include "core/io/force_log.h"
#include "core/model/model.h"
#include "core/scenario/scenario.h"
#include "core/sim/backend.h"
#include "core/sim/run_observer.h"
#include "core/run/tool_driver.h"

namespace organsim {

// Model options from the scenario: fixed selectors, gravity, per-label materials.
ModelOptions model_options(const Scenario& scenario);
// What the backend needs to know about the tool (absent => no tool pass).
BackendTool backend_tool(const Scenario& scenario);

struct RunOptions {
  std::filesystem::path outdir;       // forces.json goes here (created if missing)
  std::vector<RunObserver*> observers;  // called in this order; not owned
  // Extra entries for the log's meta (mesh source, meshing time, ...).
  nlohmann::json meta_extra = nlohmann::json::object();
  // After a topology change dt_crit is estimated again; a dt above it stops
  // the run with Error(Numerical) unless this is set (then it only warns).
  bool allow_unstable = false;
  // The tool's centre per tick from outside (organsim serve) instead of the
  // scenario's keyframes (which then only give the start); not owned.
  ToolDriver* tool_driver = nullptr;
};

struct RunResult {
  ForceLogMeta meta;
  ForceSamples samples;
  std::filesystem::path forces_path;  // empty when outputs.forces is false
  int32_t grasped_points = 0;         // pull tool: points attached at grasp time
};

// Runs the scenario's timeline on `backend` (built from `model`). If a tick or
// an observer throws, the force log is still written (valid JSON with
// "completed": false and the reason) and the error is rethrown. With
// scenario.events, the loop owns the Model versions that topology changes
// make after `model` (meta.events lists the changes).
RunResult run_scenario(const Scenario& scenario, const Model& model, Backend& backend,
                       const RunOptions& options);

// Points (internal ids) within `radius` of `center` that are free to move,
// with their offsets from the centre: what a pulling tool grasps.
Attachment select_grasp(const Model& model, const std::vector<Vec3>& positions, const Vec3& center,
                        double radius);

}  // namespace organsim
