#pragma once
// Blow-up detection during a run (docs/stability.md), for any backend.
//
// Every `interval_ticks` ticks the monitor reads the positions back (a sync
// on the GL backend, hence the interval) and checks, in this order:
//   1. non-finite positions;
//   2. energy: kinetic energy above what the run could have put in. With
//      dampers and drag only removing energy, KE <= E_elastic(start) + work of
//      gravity + work of the tool; a growing mode breaks this by orders of
//      magnitude within a few ticks while physical motion never does;
//   3. spring strain beyond a bound (default 400 % stretch);
//   4. tet inversion beyond a bound (signed volume < -3 rest volumes).
// 1 and 2 run on the tick that reads the positions (one pass over the
// points); 3 and 4, a pass over every spring and tet, are spread over that
// tick and the next interval_ticks - 1, a share each, on the positions read,
// so that no tick of a live session pays for the whole pass (at liver size
// it costs about half a 1 kHz tick's stepping). A finding therefore stops
// the run at most 2 interval_ticks - 1 ticks after it arose (plus the
// reaction's latency with BlowupMonitorOptions::reaction_positions).
// A finding stops the run: on_tick throws Error(Numerical) naming the
// simulated time, the point (input numbering) and the likely cause. The run
// loop then writes the force log with completed = false and this reason.
#include <optional>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/run_observer.h"
#include "core/stability/critical_step.h"

namespace organsim {

struct BlowupMonitorOptions {
  int32_t interval_ticks = 1;    // check every this many ticks (>= 1)
  // Geometric guards behind the energy check (which sees a growing mode
  // first). Generous on purpose: a spring lattice collapses locally without
  // exploding. Measured on scenarios/liver_push.json (2481 points) under
  // gravity alone, at any dt: slivers reach 250 % strain and V = -1.65 V_r,
  // then settle. An explosion goes far beyond both.
  double max_strain = 4.0;       // (L - r) / r beyond this stops the run
  double max_inversion = 3.0;    // V < -max_inversion V_r stops the run
  bool check_inversion = true;
  // KE > energy_factor * (budget) + floor stops the run. The slack covers the
  // measured KE (from position differences) versus Verlet's conserved energy.
  double energy_factor = 4.0;
  // Check the positions of the reaction's tick (Backend::reaction_positions,
  // reaction_latency_ticks before the tick just asked for) instead of the
  // tick's own: organsim serve, where the GL backend keeps them on the GPU
  // so that a check never waits for the tick in flight. The tick's reply
  // carries that same tick's reaction, so no client sees a state the
  // monitor has not checked; a finding comes that many ticks later.
  bool reaction_positions = false;
};

// What the monitor knows about the run, for naming the likely cause.
struct BlowupContext {
  double dt = 0;                         // s
  double tool_radius = 0;                // m: the ball about the tool origin that holds the tool; 0 = no tool
  double tool_contact_stiffness = 0;     // N/m
  std::optional<StabilityReport> stability;  // dt_crit and limiting points, when estimated
  // What bounds dt: dt_crit for Verlet, the undamped 2/omega_max for
  // implicit damping, nothing for implicit Euler (its likely causes are others).
  Integrator integrator = Integrator::Verlet;
};

struct BlowupFinding {
  enum class Kind { NonFinite, Energy, Strain, Inversion } kind = Kind::NonFinite;
  int32_t point = -1;  // input numbering
  double value = 0;    // KE (J), strain, or signed volume (m^3)
  std::string detail;  // what was seen
};

// Stateless checks 1, 3 and 4 on positions x (internal numbering).
std::optional<BlowupFinding> check_geometry(const Model& model, const std::vector<Vec3>& x,
                                            const BlowupMonitorOptions& options);

// Elastic energy of springs, the volume term and the shear element at positions x, J.
double elastic_energy(const Model& model, const std::vector<Vec3>& x);

class BlowupMonitor final : public RunObserver {
 public:
  BlowupMonitor(BlowupMonitorOptions options, BlowupContext context);
  void on_start(const Model& model, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;
  // Copies of split points start from their origin's recorded positions, so
  // the energy budget (gravity work from the start) carries on unchanged.
  void on_topology_changed(const Model& next, Backend& backend) override;

  int64_t checks() const { return checks_; }
  // The most springs and tets one tick has checked so far (3 and 4 above).
  int64_t largest_tick_scan() const { return largest_tick_scan_; }
  // The full message of a finding at simulated time t (what on_tick throws).
  std::string describe(const Model& model, const BlowupFinding& finding, double t, const TickInfo& info) const;

 private:
  std::optional<BlowupFinding> check_energy(const Model& model, double seconds) const;

  BlowupMonitorOptions options_;
  BlowupContext context_;
  std::vector<Vec3> x_, x_prev_, x_start_;  // positions now, at the previous check, at the start (npoint)
  double elastic_start_ = 0;   // J
  double tool_work_ = 0;       // J, upper bound: sum |F| |dc| over ticks
  double energy_floor_ = 0;    // J
  double last_check_t_ = 0;   // s, the time of x_
  double last_tick_t_ = 0;    // s, the end of the last tick seen
  int64_t checks_ = 0;
  // The geometric pass over x_: the share a tick checks next, or -1 when done.
  int32_t scan_share_ = -1;
  int64_t largest_tick_scan_ = 0;
};

// Cost of one check on `model` with `backend` (positions() included), for
// `organsim bench`: median of `repeats` checks, ms.
double measure_check_ms(const Model& model, Backend& backend, int repeats = 20);

}  // namespace organsim
