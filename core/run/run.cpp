#include "core/run/run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <iostream>
#include <memory>
#include <optional>

#include "core/model/material_summary.h"
#include "core/run/change_worker.h"
#include "core/run/integrator_report.h"
#include "core/sim/contact_stiffness.h"
#include "core/stability/critical_step.h"
#include "core/topology/run_events.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

ModelOptions model_options(const Scenario& scenario) {
  ModelOptions o;
  o.gravity = scenario.gravity;
  o.fixed = scenario.fixed;
  o.label_materials = scenario.materials;
  return o;
}

BackendTool backend_tool(const Scenario& scenario) {
  return scenario.tool ? scenario.tool->spec.backend_tool() : BackendTool{};
}

Attachment select_grasp(const Model& model, const std::vector<Vec3>& positions, const Vec3& center,
                        double radius) {
  Attachment a;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.fixed[i]) continue;  // a fixed point cannot follow the tool
    const Vec3 offset = positions[i] - center;
    if (offset.norm() <= radius) {
      a.points.push_back(i);
      a.offsets.push_back(offset);
    }
  }
  return a;
}

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

ForceLogMeta initial_meta(const Scenario& s, const Model& model, const Backend& backend) {
  ForceLogMeta m;
  m.scenario = s.file.string();
  m.backend = backend.name();
  m.device = backend.device();
  m.precision = backend.precision();
  m.reaction_latency_ticks = backend.reaction_latency_ticks();
  m.points = model.npoint();
  m.springs = model.nspring();
  m.tets = model.ntet();
  for (uint8_t f : model.fixed) m.fixed_points += f;
  m.dt = s.time.dt;
  m.substeps = s.time.substeps;
  m.duration = s.time.duration;
  return m;
}

// A tick event (grasp, release) happens at the first tick that starts at or
// after its time; half a step of slack absorbs rounding in i * tick.
bool starts_at_or_after(double tick_start, double event_time, double dt) {
  return tick_start >= event_time - 0.5 * dt;
}

// After a topology change the run's dt must still be below dt_crit of the
// new Model (a cut should not lower it, docs/topology.md; this checks it).
void check_step_after_change(const StabilityReport& report, const Scenario& s, double t, bool allow_unstable) {
  try {
    const std::string warning = check_time_step(report, s.time.dt, s.time.substeps, allow_unstable, s.time.integrator);
    if (!warning.empty()) std::cerr << "organsim: after the topology change at t = " << t << " s: " << warning << "\n";
  } catch (const Error& e) {
    throw Error(e.kind(), "after the topology change at t = " + std::to_string(t) + " s: " + e.what());
  }
}

}  // namespace

RunResult run_scenario(const Scenario& scenario, const Model& model, Backend& backend,
                       const RunOptions& options) {
  RunResult result;
  result.meta = initial_meta(scenario, model, backend);
  result.meta.extra = options.meta_extra;
  result.meta.extra["elasticity"] = model_elasticity_json(model);
  if (scenario.outputs.forces) result.forces_path = options.outdir / "forces.json";

  const TimeDef& time = scenario.time;
  const int64_t nticks = time.ticks();
  const double tick = time.tick();
  const ToolSpec* tool = scenario.tool ? &scenario.tool->spec : nullptr;
  const bool pull = tool && tool->mode == ToolMode::Pull;
  result.samples.reserve(static_cast<size_t>(nticks));
  if (tool && tool->shape == ToolShape::Grasper) {
    result.samples.grip.reserve(static_cast<size_t>(nticks));
    result.samples.jaw_gap.reserve(static_cast<size_t>(nticks));
  }

  // Sized once here: the loop itself allocates nothing except at a grasp.
  std::vector<Vec3> positions;
  if (pull) positions.reserve(static_cast<size_t>(model.npoint()));
  bool grasped = false, released = false;
  Mat3 held_stiffness = Mat3::Zero();  // TickInfo::held_stiffness

  // Topology changes: for a scenario with events, or a tool driver, which
  // may ask for a cut at any tick. Made here, before the first tick: the
  // face table and the stable step's rows cost 0.2 s at 7.7k points and
  // 0.8 s at 28k, more than a tick can spare. `current` is the Model the
  // backend steps now; versions after `model` are owned here.
  std::optional<TopologyEvents> topology;
  if (scenario.events.any() || options.tool_driver) topology.emplace(scenario.events, model);
  std::unique_ptr<Model> owned;
  const Model* current = &model;
  std::vector<Vec3> event_positions;
  double suture_tension_peak = 0;  // N, at the end of any tick (meta.sutures.tension_max_N)

  // A change being built off the tick's path (cuts marked for it); declared
  // after `topology` so that it is done before they go.
  ChangeWorker off_path;
  bool off_path_driver_cut = false;  // the change the worker builds holds the tool driver's cut
  const ToolSpec* tool_spec = scenario.tool ? &scenario.tool->spec : nullptr;
  // Makes `next`, the version `topology` made from *current, the Model the
  // backend steps from the tick starting at t0. `built`: what the worker made
  // off the tick's path (the guaranteed-stable step and the backend's
  // prepared tables, which leave only their adoption on the tick); `applied_t`:
  // t0 when that is later than the tick that made it.
  const auto adopt = [&](std::unique_ptr<Model> next, double t0, ChangeWorker::Built* built,
                         std::optional<double> applied_t) {
    const auto rebuild_start = Clock::now();
    if (built) {
      backend.adopt(std::move(built->prepared));
    } else {
      backend.rebuild(*next);
    }
    const double rebuild_seconds = seconds_since(rebuild_start);
    // From here the backend steps `next`; the previous version lives until
    // the end of this call (the log compares the two).
    const std::unique_ptr<Model> previous_owned = std::move(owned);
    const Model& previous = *current;
    owned = std::move(next);
    current = owned.get();
    for (RunObserver* o : options.observers) o->on_topology_changed(*current, backend);
    // dt below the guaranteed (Gershgorin) step is stable, and the full
    // estimate would accept it too; only above it is the power iteration
    // needed to decide. A change built off the tick's path had both made on
    // the worker.
    ChangeTimes times;
    times.rebuild_seconds = rebuild_seconds;
    double guaranteed = 0;
    std::optional<StabilityReport> report;
    if (built) {
      guaranteed = built->guaranteed;
      report = std::move(built->full);
      times.prepare_seconds = built->prepare_seconds;
      times.check_prepare_seconds = built->check_seconds;
    } else {
      const auto check_start = Clock::now();
      const CriticalStepOptions step_options = critical_step_options(*current, tool_spec);
      guaranteed = topology->guaranteed_step(previous, *current, step_options);
      if (!(time.dt <= guaranteed)) report = estimate_critical_step(*current, step_options);
      times.check_seconds = seconds_since(check_start);
    }
    topology->changed(previous, *current, times, guaranteed, report ? &*report : nullptr, applied_t);
    if (report) check_step_after_change(*report, scenario, t0, options.allow_unstable);
  };
  // Swaps in the change built off the tick's path at the tick starting at t0.
  const auto finish_off_path = [&](double t0) {
    ChangeWorker::Built built = off_path.take();
    if (built.next) adopt(std::move(built.next), t0, &built, t0);
    if (off_path_driver_cut) options.tool_driver->cut_applied(t0);
    off_path_driver_cut = false;
  };

  TickRequest request;
  request.dt = time.dt;
  request.substeps = time.substeps;
  request.tool_active = tool != nullptr;

  const auto loop_start = Clock::now();
  double step_seconds = 0;
  int64_t ticks_done = 0;
  bool finish_called = false;
  std::exception_ptr failure;
  try {
    for (RunObserver* o : options.observers) o->on_start(model, backend);
    for (int64_t i = 0; i < nticks; ++i) {
      const double t0 = static_cast<double>(i) * tick;
      const double t1 = static_cast<double>(i + 1) * tick;
      bool driver_cut = false;  // the tool driver asked for a cut over this tick
      if (tool) {
        // A tick starts where the last one ended (the same double t0 as the
        // last tick's t1, so identical to position_at(t0) for keyframes).
        request.tool_from = i == 0 ? tool->position_at(t0) : request.tool_to;
        request.turn_from = i == 0 ? tool->orientation_at(t0) : request.turn_to;
        request.turn_to = tool->orientation_at(t1);
        request.gap_from = i == 0 ? tool->gap_at(t0) : request.gap_to;
        request.gap_to = tool->gap_at(t1);
        if (options.tool_driver) {
          const std::optional<Vec3> to = options.tool_driver->tool_at_end_of(i, t1);
          if (!to) break;
          request.tool_to = *to;
          if (std::optional<CutEvent> cut = options.tool_driver->cut_for_tick()) {
            driver_cut = true;
            if (off_path.busy()) finish_off_path(t0);  // the events change only while the worker is idle
            topology.value().add_cut(std::move(*cut));  // made before the first tick
          }
        } else {
          request.tool_to = tool->position_at(t1);
        }
      }
      // A change built off the tick's path goes in at its tick, or before any other change.
      if (off_path.busy() && (off_path.due(t0, time.dt) || topology->active(t0, t1))) finish_off_path(t0);
      if (topology && topology->active(t0, t1)) {
        backend.positions(event_positions);
        const OffPathPlan plan = topology->off_path(t0, t1, time.dt);
        if (plan.off) {
          off_path.start(*topology, *current, event_positions, t0, t1, time.dt, tool_spec, backend, plan);
          off_path_driver_cut = driver_cut;
        } else {
          auto next = std::make_unique<Model>();
          if (topology->before_tick(t0, t1, *current, event_positions, *next))
            adopt(std::move(next), t0, nullptr, std::nullopt);
          if (driver_cut) options.tool_driver->cut_applied(t0);  // with the tick's other events, at once
        }
      }
      if (pull && !grasped && starts_at_or_after(t0, tool->grasp_time, time.dt)) {
        backend.positions(positions);
        const Attachment a = select_grasp(*current, positions, request.tool_from, tool->grasp_radius);
        result.grasped_points = static_cast<int32_t>(a.points.size());
        backend.attach(a);
        held_stiffness = attachment_stiffness(*current, a, tool->contact_stiffness);
        grasped = true;
      }
      if (pull && grasped && !released && tool->release_time &&
          starts_at_or_after(t0, *tool->release_time, time.dt)) {
        backend.release();
        held_stiffness.setZero();
        released = true;
      }

      const auto step_start = Clock::now();
      const Reaction r = backend.tick(request);
      step_seconds += seconds_since(step_start);
      ++ticks_done;
      // The blow-up checks run every few ticks; a reaction that is already
      // non-finite stops the run here, so the force log never holds a NaN.
      if (!r.force.allFinite() || !r.torque.allFinite()) {
        throw Error(ErrorKind::Numerical, "run stopped at t = " + format_number(t1, "%.6g") +
                                              " s: the tool's reaction force is not finite (the simulation blew up; "
                                              "a smaller time.dt or more substeps keeps it stable)");
      }

      result.samples.push(t1, r.force, r.torque, request.tool_to, r.contacts);
      if (tool && tool->shape == ToolShape::Grasper) {
        result.samples.grip.push_back(r.grip);
        result.samples.jaw_gap.push_back(request.gap_to);
      }
      if (current->nsuture() > 0) {
        backend.positions(event_positions);
        suture_tension_peak = std::max(suture_tension_peak, suture_tension_max(*current, event_positions, t1));
      }
      TickInfo info;
      info.tick = i;
      info.t = t1;
      info.tool_center = request.tool_to;
      info.tool_orientation = request.turn_to;
      info.tool_from = request.tool_from;
      info.tool_active = request.tool_active;
      info.reaction = r;
      info.held_stiffness = held_stiffness;
      for (RunObserver* o : options.observers) o->on_tick(*current, backend, info);
    }
    off_path.abandon();  // a change not swapped in by the last tick never is
    finish_called = true;
    for (RunObserver* o : options.observers) o->on_finish(*current, backend);
    result.meta.completed = true;
  } catch (const std::exception& e) {
    off_path.abandon();
    result.meta.completed = false;
    result.meta.stop_reason = e.what();
    failure = std::current_exception();
  }

  const int64_t steps = ticks_done * time.substeps;
  result.meta.wall_seconds = seconds_since(loop_start);
  result.meta.steps_per_second = step_seconds > 0 ? static_cast<double>(steps) / step_seconds : 0;
  result.meta.real_time_factor =
      result.meta.wall_seconds > 0 ? static_cast<double>(ticks_done) * tick / result.meta.wall_seconds : 0;
  // The CPU backend may change its thread count during the run (thread_choice.h).
  if (const std::string device = backend.device(); device != result.meta.device)
    result.meta.extra["device_at_end"] = device;
  result.meta.extra["integrator"] = integrator_meta(backend);
  result.meta.extra["step_seconds"] = step_seconds;
  result.meta.extra["steps"] = steps;
  if (pull) result.meta.extra["grasped_points"] = result.grasped_points;
  if (topology && (scenario.events.any() || !topology->log().empty())) {
    result.meta.extra["events"] = topology->log();
    result.meta.extra["final_points"] = current->npoint();
    result.meta.extra["final_springs"] = current->nspring();
    if (!failure && !scenario.events.sutures.empty()) {
      backend.positions(event_positions);
      result.meta.extra["sutures"] = suture_summary(*current, event_positions, backend.time(), suture_tension_peak);
    }
  }

  if (options.tool_driver) options.tool_driver->add_meta(result.meta.extra);

  if (failure) {
    // Keep what was recorded, say why it stopped, then let the caller report it.
    if (!finish_called) {
      for (RunObserver* o : options.observers) {
        try {
          o->on_finish(*current, backend);
        } catch (...) {
          // The first error is the one to report.
        }
      }
    }
    if (!result.forces_path.empty()) write_force_log(result.forces_path, result.meta, result.samples);
    std::rethrow_exception(failure);
  }
  if (!result.forces_path.empty()) write_force_log(result.forces_path, result.meta, result.samples);
  return result;
}

}  // namespace organsim
