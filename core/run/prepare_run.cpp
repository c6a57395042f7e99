#include "core/run/prepare_run.h"

#include <cmath>

#include "core/run/run.h"
#include "core/util/error.h"

namespace organsim {

Model build_scenario_model(const Scenario& scenario, const TetMesh& mesh, const Material& material) {
  try {
    return build_model(mesh, material, model_options(scenario), scenario.mesh.path.string());
  } catch (const Error& e) {
    // build_model names the JSON path (fixed[0].indices[3]) but not the file.
    if (e.kind() == ErrorKind::Scenario) throw Error(e.kind(), scenario.file.string() + ": " + e.what());
    throw;
  }
}

PreparedRun prepare_run(const Scenario& scenario, const Model& model, const PrepareRunOptions& options) {
  PreparedRun prepared;
  const ToolSpec* tool = scenario.tool ? &scenario.tool->spec : nullptr;
  prepared.stability = estimate_critical_step(model, critical_step_options(model, tool));
  if (options.settle && scenario.time.settle > 0) {
    const TimeDef& time = scenario.time;
    SettleOptions settle_options;
    settle_options.seconds = time.settle;
    settle_options.dt = time.dt;
    settle_options.substeps = time.substeps;
    settle_options.threads = options.threads;
    settle_options.integrator = time.integrator;
    settle_options.implicit = time.implicit;
    // The equilibrium does not depend on the step, and the run refuses (or
    // adapts) an unstable one only after this: a step above the limit of
    // the settle's integrator is replaced by a stable one that keeps the
    // tick, so that settling never diverges into a start of NaN.
    const StabilityReport& st = prepared.stability;
    if (time.integrator == Integrator::Verlet && time.dt > st.dt_crit) {
      const StepSuggestion step = suggest_step(st, time.tick());
      settle_options.dt = step.dt;
      settle_options.substeps = step.substeps;
    } else if (time.integrator == Integrator::ImplicitDamping && time.dt > st.dt_crit_undamped) {
      settle_options.substeps = static_cast<int32_t>(std::ceil(time.tick() / (0.9 * st.dt_crit_undamped)));
      settle_options.dt = time.tick() / settle_options.substeps;
    }
    prepared.settled = settle(model, settle_options);
  }
  return prepared;
}

BlowupMonitor PreparedRun::blowup_monitor(const Scenario& scenario, double dt, int32_t interval_ticks,
                                          bool reaction_positions) const {
  BlowupMonitorOptions options;
  options.interval_ticks = interval_ticks;
  options.reaction_positions = reaction_positions;
  BlowupContext context;
  context.dt = dt;
  if (scenario.tool) {
    context.tool_radius = scenario.tool->spec.radius + scenario.tool->spec.extent();  // the ball holding the tool
    context.tool_contact_stiffness = scenario.tool->spec.contact_stiffness;
  }
  context.stability = stability;
  context.integrator = scenario.time.integrator;
  return BlowupMonitor(options, context);
}

void PreparedRun::start(Backend& backend) const {
  if (settled) backend.set_state(settled->positions, settled->positions);
}

nlohmann::json PreparedRun::meta() const {
  nlohmann::json j;
  j["dt_crit"] = stability.dt_crit;
  j["stability"] = to_json(stability);
  j["settle"] = settled ? to_json(*settled) : nlohmann::json(nullptr);
  return j;
}

}  // namespace organsim
