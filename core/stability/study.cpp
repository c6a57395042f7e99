#include "core/stability/study.h"

#include <algorithm>
#include <cmath>

#include "core/sim/backend.h"

namespace organsim {

void PositionSampler::on_tick(const Model& /*model*/, Backend& backend, const TickInfo& info) {
  if ((info.tick + 1) % every_ != 0) return;
  out_.ticks.push_back(info.tick);
  out_.positions.emplace_back();
  backend.positions(out_.positions.back());
}

StudyErrors compare_trajectories(const Trajectory& run, const Trajectory& reference, double diag) {
  StudyErrors e;
  double sum2 = 0;
  int64_t count = 0;
  size_t j = 0;
  for (size_t i = 0; i < run.ticks.size(); ++i) {
    while (j < reference.ticks.size() && reference.ticks[j] < run.ticks[i]) ++j;
    if (j == reference.ticks.size() || reference.ticks[j] != run.ticks[i]) continue;
    const auto& a = run.positions[i];
    const auto& b = reference.positions[j];
    for (size_t p = 0; p < std::min(a.size(), b.size()); ++p) {
      const double d = (a[p] - b[p]).norm() / diag;
      e.position_max = std::max(e.position_max, std::isfinite(d) ? d : INFINITY);
      sum2 += d * d;
      ++count;
    }
    ++e.samples;
  }
  e.position_rms = count > 0 ? std::sqrt(sum2 / count) : 0;

  double peak = 0;
  for (const Vec3& f : reference.force) peak = std::max(peak, f.norm());
  double fsum2 = 0;
  for (int64_t t = 0;; ++t) {
    const int64_t ra = t + run.latency_ticks, rb = t + reference.latency_ticks;
    if (ra >= static_cast<int64_t>(run.force.size()) || rb >= static_cast<int64_t>(reference.force.size())) break;
    fsum2 += (run.force[ra] - reference.force[rb]).squaredNorm();
    ++e.ticks;
  }
  e.force_rms = peak > 0 && e.ticks > 0 ? std::sqrt(fsum2 / e.ticks) / peak : 0;
  return e;
}

std::vector<bool> pareto_front(const std::vector<double>& cost, const std::vector<double>& error) {
  const size_t n = cost.size();
  std::vector<bool> front(n, false);
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(cost[i]) || !std::isfinite(error[i])) continue;
    bool dominated = false;
    for (size_t j = 0; j < n && !dominated; ++j) {
      if (j == i || !std::isfinite(cost[j]) || !std::isfinite(error[j])) continue;
      dominated = cost[j] <= cost[i] && error[j] <= error[i] && (cost[j] < cost[i] || error[j] < error[i]);
    }
    front[i] = !dominated;
  }
  return front;
}

}  // namespace organsim
