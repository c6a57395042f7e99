#pragma once
// What every driver of a scenario run (`organsim run`, `study`, `fit`, and
// any later one) sets up the same way before the loop: the Model from the
// scenario, the stability estimate at rest with the scenario's tool, the
// blow-up monitor's context, the start at rest under gravity (time.settle)
// and what these add to the force log's meta. The drivers differ only in
// what they do with a dt above dt_crit (refuse, adapt, or compare).
#include <nlohmann/json.hpp>

#include <optional>

#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/run/settle.h"
#include "core/scenario/scenario.h"
#include "core/sim/backend.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"

namespace organsim {

// build_model with the scenario's fixed points and gravity; a scenario error
// (a fixed selector that selects nothing, ...) names the scenario file.
Model build_scenario_model(const Scenario& scenario, const TetMesh& mesh, const Material& material);
inline Model build_scenario_model(const Scenario& scenario, const TetMesh& mesh) {
  return build_scenario_model(scenario, mesh, scenario.material);
}

struct PrepareRunOptions {
  bool settle = true;     // bring the model to rest first when the scenario asks (time.settle > 0)
  int32_t threads = 0;    // CPU threads for settling (0: all)
};

struct PreparedRun {
  StabilityReport stability;            // dt_crit at rest, the scenario's tool included
  std::optional<SettleResult> settled;  // the equilibrium the run starts from (time.settle > 0)

  // The blow-up monitor for a run at step dt (s), checking every
  // `interval_ticks` ticks (a backend's default_check_interval_ticks(), or 1
  // to see a blow-up at the tick it starts).
  // reaction_positions: BlowupMonitorOptions::reaction_positions (organsim serve).
  BlowupMonitor blowup_monitor(const Scenario& scenario, double dt, int32_t interval_ticks,
                               bool reaction_positions = false) const;
  // Puts the backend at the settled start with zero velocity (nothing without settle).
  void start(Backend& backend) const;
  // {"dt_crit", "stability", "settle"} for the force log's meta.
  nlohmann::json meta() const;
};

PreparedRun prepare_run(const Scenario& scenario, const Model& model, const PrepareRunOptions& options = {});

}  // namespace organsim
