#pragma once
// What every simulator backend (cpu, gl) offers the run loop. A backend owns
// its State (x_t, x_{t-1}) in whatever precision and memory it likes; the
// Model it was built from is immutable and outlives it.
#include <memory>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/step_plan.h"
#include "core/sim/tool.h"

namespace organsim {

// One haptic tick: `substeps` Verlet steps of `dt`; the tool frame's origin
// moves linearly from tool_from (start of tick) to tool_to (end of tick) and
// its orientation turns by slerp from turn_from to turn_to (a sphere
// ignores it), and a grasper's jaws move linearly from gap_from to gap_to.
struct TickRequest {
  double dt = 1e-4;  // s
  int32_t substeps = 10;
  bool tool_active = false;
  Vec3 tool_from{0, 0, 0}, tool_to{0, 0, 0};  // m
  Quat turn_from = Quat::Identity(), turn_to = Quat::Identity();
  double gap_from = 0, gap_to = 0;  // grasper: the jaws' gap, m

  // The tool at the start of substep s (of `substeps`): where its force acts.
  ToolPlacement tool_at(const BackendTool& tool, int32_t s) const {
    const double f = static_cast<double>(s) / substeps;
    const Vec3 origin = tool_from + f * (tool_to - tool_from);
    if (tool.shape == ToolShape::Sphere) return place_tool(tool, origin, Quat::Identity());
    return place_tool(tool, origin, turn_from.slerp(f, turn_to), gap_from + f * (gap_to - gap_from));
  }
};

// What a backend does for a scene, for `organsim run --plan`: the step
// plan's passes in order (core/sim/step_plan.h: the same names on every
// backend), each with this backend's detail, the work it does once per tick
// outside the step, and its buffers.
struct PassInfo {
  std::string name;    // pass_name() for a step pass, e.g. "springs", "volume", "tool-contact", "integrate"
  std::string detail;  // how this backend runs it, sizes
};
struct BufferInfo {
  std::string name;
  size_t bytes = 0;
};
struct Plan {
  std::vector<PassInfo> passes;      // the step plan's passes, in order
  std::vector<PassInfo> per_tick;    // once per tick, outside the step (GL: reaction reduction, readback)
  std::vector<BufferInfo> buffers;
  int32_t dispatches_per_step = 0;   // GL: compute dispatches; CPU: fused loops
  int32_t syncs_per_step = 0;        // CPU-GPU synchronisations per step
};

// What an implicit integrator's linear solves did so far in a run (the
// force log's meta and the progress line; core/sim/reference_backend.h).
struct IntegratorStats {
  std::vector<int32_t> cg_iterations;  // per step, summed over its Newton iterations
  double max_residual = 0;             // the largest final relative CG residual of any solve
  int64_t unconverged_steps = 0;       // steps with a solve that stopped above its tolerance
  int32_t cg_max_iterations = 0;       // the limit a solve stops at
  double cg_seconds = 0;               // wall time inside the solves (organsim bench: per CG iteration)
  // Steps whose velocity change turned back the last one's, about as large
  // (cosine below -0.9, at least half its size) and not negligible: a state
  // alternating between two, which a converged CG does not show (a stiff
  // contact overshot by one linearisation per step).
  int64_t alternating_steps = 0;
  // With Newton iterations: |M (v1 - v0) - h f(x0 + h v1, v1)| on the free
  // coordinates after the first solve and after each Newton step, of the
  // last step (N s); empty with one linearised solve per step.
  std::vector<double> last_newton_residuals;
  int64_t steps() const { return static_cast<int64_t>(cg_iterations.size()); }
};

// A Model version packed by Backend::prepare, for adopt() on the backend
// that made it. `next` must outlive it and the backend.
class PreparedModel {
 public:
  explicit PreparedModel(const Model& next) : next_(&next) {}
  virtual ~PreparedModel() = default;
  const Model& model() const { return *next_; }

 private:
  const Model* next_;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;    // "cpu", "gl"
  virtual std::string device() const = 0;  // CPU model or GL_RENDERER
  virtual std::string precision() const = 0;  // "double" or "float"
  virtual Plan plan() const = 0;
  // The passes of the current Model's step (recomputed at every rebuild).
  virtual const StepPlan& step_plan() const = 0;

  // Ticks between a tick and the tick() call that returns its reaction:
  // 0 on the CPU, 1 for the GL backend's non-blocking readback.
  virtual int32_t reaction_latency_ticks() const = 0;

  // Default ticks between two full blow-up checks (core/stability/
  // blowup_monitor.h), which read the positions back. On the CPU a check costs
  // about one step, so every 10 ticks. A backend that flags non-finite
  // positions on its device every tick can check the rest less often: on a
  // GPU the readback drains the pipeline (docs/gl.md "On a GPU").
  virtual int32_t default_check_interval_ticks() const { return 10; }

  // Runs one tick and returns the tool reaction at the end of the tick that
  // is reaction_latency_ticks() old (zero reaction until the first one).
  virtual Reaction tick(const TickRequest& request) = 0;

  // Pull tool: attach / release points (internal ids).
  virtual void attach(const Attachment& attachment) = 0;
  virtual void release() = 0;

  // Current positions x_t, in internal numbering (may synchronise a GPU).
  virtual void positions(std::vector<Vec3>& out) const = 0;
  // The positions at the end of the tick whose reaction the last tick()
  // returned: the state that reaction was computed from (organsim serve's
  // contact stiffness is evaluated on it). With no latency these are
  // positions(); the GL backend keeps a copy of each tick's on the GPU
  // (GlBackendOptions::keep_reaction_positions), so that reading them never
  // waits for the tick in flight.
  virtual void reaction_positions(std::vector<Vec3>& out) const { positions(out); }
  // Replaces x_t and x_{t-1} (internal numbering), e.g. to start from a
  // deformed or moving state in tests. Not for use inside a run.
  virtual void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) = 0;
  // The Model changed topology (model_rebuild.h: ids kept, points appended):
  // re-packs everything from `next`, which must outlive the backend or the
  // next rebuild. x_t and x_{t-1} of existing points carry over exactly;
  // appended points start with the x_t and x_{t-1} of the point they copy
  // (Model::origin), so a cut adds no velocity jump. Attachments stay on the
  // same ids. Between ticks only. The same as adopt(prepare(next)).
  void rebuild(const Model& next) { adopt(prepare(next)); }
  // The part of a rebuild that needs nothing of the run: `next` packed into
  // this backend's tables (precision, slot order, kernel streams, host-side
  // buffer contents). Changes nothing and reads no state, so a run may call
  // it on another thread while this backend ticks (the topology change's
  // worker, core/run/change_worker.h).
  virtual std::unique_ptr<PreparedModel> prepare(const Model& next) const = 0;
  // The rest of the rebuild, between ticks: the state carried over by ids
  // as rebuild() says, the prepared tables swapped in (GL: uploaded). Ticks
  // after adopt(prepare(next)) are bit for bit those after rebuild(next),
  // however many ticks ran between the two calls.
  virtual void adopt(std::unique_ptr<PreparedModel> prepared) = 0;
  // Simulated time at the end of the last tick, s.
  virtual double time() const = 0;
  // The implicit integrator's solver statistics; null for an explicit one.
  virtual const IntegratorStats* integrator_stats() const { return nullptr; }
};

}  // namespace organsim
