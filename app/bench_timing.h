#pragma once
// How `organsim bench` times a backend: warm-up, then repetitions of a tick
// of many substeps, each closed by a read-back of the positions (so an
// asynchronous backend is timed until its work is done); median, fastest and
// slowest repetition per step. Shared by the size table (cmd_bench.cpp) and
// the material comparison (bench_materials.cpp), so both measure alike.
#include <cstdint>
#include <string>
#include <vector>

#include "core/sim/backend.h"

namespace organsim::app {

struct BenchTiming {
  double median_ms = 0, min_ms = 0, max_ms = 0;  // per step
};

struct BenchSteps {
  int32_t warmup = 200;       // steps before timing
  int32_t repetitions = 7;    // timed ticks
  int32_t steps = 200;        // substeps per timed tick
};

// `v` with `digits` digits after the point ("0.4490"): the bench tables' numbers.
std::string fixed(double v, int digits);

// Median (mean of the two middle ones for an even count), min and max of `ms`.
BenchTiming summarise_ms(std::vector<double> ms);

// A pushing sphere of `radius` m placed under the lowest of the positions
// and pressed `depth` m into it before every tick (radius 0: no tool).
struct BenchToolPlacement {
  double radius = 0, depth = 0;
};

// One tick of `steps` substeps at `dt` (s), closed by a position read-back
// into `positions` (which place the tool): ms per step.
double time_steps(Backend& backend, int32_t steps, double dt, std::vector<Vec3>& positions,
                  const BenchToolPlacement& tool = {});

// Warm-up, then `repetitions` ticks of `steps` substeps at `dt` (s), each
// closed by a position read-back; per-step times from each.
BenchTiming time_backend(Backend& backend, const BenchSteps& steps, double dt, std::vector<Vec3>& positions,
                         const BenchToolPlacement& tool = {});

}  // namespace organsim::app
