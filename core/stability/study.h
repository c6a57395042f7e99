#pragma once
// Error against run time (docs/stability.md): what `organsim study` measures
// for each configuration against a converged reference. Plain data and maths
// here; running the configurations and writing files is app/cmd_study.cpp.
#include <cstdint>
#include <vector>

#include "core/sim/run_observer.h"
#include "core/util/vec.h"

namespace organsim {

// What a run leaves for comparison: positions every `every` ticks and the
// tool force at every tick.
struct Trajectory {
  std::vector<int64_t> ticks;                   // tick index of each position sample
  std::vector<std::vector<Vec3>> positions;     // internal numbering, m (nsample x npoint)
  std::vector<Vec3> force;                      // tool reaction per tick, N (ntick)
  int32_t latency_ticks = 0;                    // the backend's reaction latency
};

// Records positions every `every` ticks (a readback: keep `every` large on GL).
class PositionSampler final : public RunObserver {
 public:
  PositionSampler(int64_t every, Trajectory& out) : every_(every < 1 ? 1 : every), out_(out) {}
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;

 private:
  int64_t every_;
  Trajectory& out_;
};

struct StudyErrors {
  double position_max = 0;  // max over samples and points of |x - x_ref| / bbox diagonal
  double position_rms = 0;  // RMS over samples and points of the same
  double force_rms = 0;     // RMS over ticks of |F - F_ref| / max |F_ref| (0 when the reference has no force)
  int64_t samples = 0;      // position samples compared
  int64_t ticks = 0;        // force ticks compared
};

// Compares `run` with `reference` on the ticks both have; forces are aligned
// by each side's reaction latency.
StudyErrors compare_trajectories(const Trajectory& run, const Trajectory& reference, double bbox_diagonal);

// Pareto front of points minimising both cost and error: true where no other
// point is at least as good in both and better in one. Non-finite entries
// (unstable runs) are never on it.
std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error);

}  // namespace organsim
