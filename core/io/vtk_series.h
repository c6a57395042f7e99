#pragma once
// The ParaView time series: a RunObserver that writes the model's state at
// `rate` states per simulated second as OUTDIR/vtk/state_NNNNN.vtu (tets in
// the current configuration) or .vtp (boundary triangles only), in the user's
// point numbering, and keeps OUTDIR/states.pvd listing them with their times.
// The .pvd is rewritten (atomically) after every state, so a run that stops
// early still leaves a series ParaView opens.
//
// Point data: displacement (x - X, m), velocity (mean over the last haptic
// tick, m/s; zero in the first state, which is at rest), fixed (1 for fixed
// points), tool_force (push tool only: the contact force on each point, N).
// Cell data (.vtu): volume_ratio V / V_r, max_spring_strain (largest
// |L - r| / r over the tet's six edges). Surface files carry point_id, the
// user's number of each point.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/scenario/outputs.h"
#include "core/sim/run_observer.h"
#include "core/scenario/tool_spec.h"

namespace organsim {

class VtkSeriesRecorder : public RunObserver {
 public:
  // tick: the haptic tick, s (velocities are differences over one tick).
  // tool: its contact force is written for a push tool; nullopt without one.
  VtkSeriesRecorder(const VtkSeriesDef& def, const std::filesystem::path& outdir, double tick,
                    std::optional<ToolSpec> tool);

  void on_start(const Model& model, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;

  int states_written() const { return static_cast<int>(steps_.size()); }

 private:
  void write_state(const Model& model, double t, const Vec3& tool_center, const Quat& tool_turn, bool have_previous);

  VtkSeriesDef def_;
  std::filesystem::path outdir_;
  double tick_;
  std::optional<ToolSpec> tool_;
  int next_due_ = 0;                 // state k is due at t = k / rate
  std::vector<Vec3> positions_;      // internal numbering, reused
  std::vector<Vec3> previous_;       // positions one tick before the state, internal numbering
  std::vector<std::pair<double, std::string>> steps_;  // (t, file relative to OUTDIR) for the .pvd
};

}  // namespace organsim
