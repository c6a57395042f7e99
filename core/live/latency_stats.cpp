#include "core/live/latency_stats.h"

#include <algorithm>
#include <cmath>

namespace organsim {

namespace {

// The nearest-rank q-quantile: the smallest value with at least q of the
// values at or below it.
double quantile(std::vector<double>& v, double q) {
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())));
  const size_t k = rank == 0 ? 0 : rank - 1;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

LatencySummary summarise_latency(std::vector<double>& seconds) {
  LatencySummary s;
  s.count = seconds.size();
  if (seconds.empty()) return s;
  s.median = quantile(seconds, 0.5);
  s.p99 = quantile(seconds, 0.99);
  s.max = *std::max_element(seconds.begin(), seconds.end());
  return s;
}

nlohmann::json latency_json(const LatencySummary& s) {
  return {{"count", s.count}, {"median_ms", s.median * 1e3}, {"p99_ms", s.p99 * 1e3}, {"max_ms", s.max * 1e3}};
}

}  // namespace organsim
