#pragma once
// OUTDIR/forces.png during `organsim run`: a RunObserver that keeps the tool
// reaction of every tick and draws the plot when the run finishes (also when
// it stopped on an error: the plot then shows the run up to the failure).
#include <filesystem>
#include <vector>

#include "core/render/force_plot.h"
#include "core/sim/run_observer.h"

namespace organsim {

class ForcePlotRecorder : public RunObserver {
 public:
  // tick: haptic tick length, s; expected_ticks sizes the sample arrays once.
  ForcePlotRecorder(const std::filesystem::path& path, double tick, int64_t expected_ticks);
  void on_start(const Model& model, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;
  void on_finish(const Model& model, Backend& backend) override;

 private:
  std::filesystem::path path_;
  double tick_ = 0;
  int32_t latency_ = 0;
  std::vector<double> t_;
  std::vector<Vec3> force_;
};

}  // namespace organsim
