#pragma once
// The start at rest under load (scenario `time.settle`): before t = 0 the
// model is brought to equilibrium under gravity and its fixed points, with no
// tool, by dynamic relaxation with kinetic damping: the double-precision CPU
// backend steps the model (with the run's integrator), and whenever the kinetic energy passes a peak all
// velocities are set to zero, so the energy drains into the equilibrium
// instead of oscillating about it. The run then starts from these positions
// with zero velocity, so the force log, frames and study show only the tool.
#include <nlohmann/json_fwd.hpp>

#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/reference_backend.h"

namespace organsim {

struct SettleOptions {
  double seconds = 0;       // most simulated time to spend, s (> 0)
  double dt = 1e-4;         // s, the run's step
  int32_t substeps = 10;    // steps per tick (energy is checked per tick)
  int32_t threads = 0;      // CPU threads (0: all)
  // Stop early once the largest net force on a free point is below this
  // fraction of the heaviest point's weight.
  double tolerance = 1e-4;
  // The run's integrator: with an implicit one (whose dt may exceed
  // dt_crit) the settling steps are implicit too (`implicit` says how).
  Integrator integrator = Integrator::Verlet;
  ImplicitOptions implicit;
};

struct SettleResult {
  std::vector<Vec3> positions;     // internal numbering, at equilibrium
  double seconds = 0;              // simulated settling time used, s
  int64_t ticks = 0;
  bool converged = false;          // residual below tolerance before `seconds` ran out
  double residual_force = 0;       // largest net force on a free point at rest there, N
  double residual_relative = 0;    // residual_force / heaviest point's weight (0 without gravity)
  double max_displacement = 0;     // largest distance from the rest state, m (the sag)
  double wall_seconds = 0;
};

SettleResult settle(const Model& model, const SettleOptions& options);

// One line for the console: time, sag, residual and whether it converged.
std::string describe(const SettleResult& result);

// {seconds, ticks, converged, residual_force_N, residual_relative, max_displacement_m, wall_seconds}
nlohmann::json to_json(const SettleResult& result);

}  // namespace organsim
