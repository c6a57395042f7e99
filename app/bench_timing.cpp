#include "app/bench_timing.h"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>

namespace organsim::app {

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

BenchTiming summarise_ms(std::vector<double> ms) {
  std::sort(ms.begin(), ms.end());
  BenchTiming t;
  t.min_ms = ms.front();
  t.max_ms = ms.back();
  const size_t n = ms.size();
  t.median_ms = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  return t;
}

double time_steps(Backend& backend, int32_t steps, double dt, std::vector<Vec3>& positions,
                  const BenchToolPlacement& tool) {
  TickRequest request;
  request.dt = dt;
  request.tool_active = tool.radius > 0;
  request.substeps = steps;
  if (request.tool_active) {
    if (positions.empty()) backend.positions(positions);
    const Vec3 low = *std::min_element(positions.begin(), positions.end(),
                                       [](const Vec3& a, const Vec3& b) { return a.z() < b.z(); });
    request.tool_from = request.tool_to = low - Vec3(0, 0, tool.radius - tool.depth);
  }
  const auto start = std::chrono::steady_clock::now();
  if (steps > 0) backend.tick(request);
  backend.positions(positions);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return steps > 0 ? 1e3 * seconds / steps : 0;
}

BenchTiming time_backend(Backend& backend, const BenchSteps& steps, double dt, std::vector<Vec3>& positions,
                         const BenchToolPlacement& tool) {
  time_steps(backend, steps.warmup, dt, positions, tool);
  std::vector<double> ms;
  for (int32_t r = 0; r < steps.repetitions; ++r) ms.push_back(time_steps(backend, steps.steps, dt, positions, tool));
  return summarise_ms(std::move(ms));
}

}  // namespace organsim::app
