#pragma once
// Reply latency (receipt of a pose to the force reply of the tick that
// applied it) summarised as median, 99th percentile and maximum.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <vector>

namespace organsim {

struct LatencySummary {
  size_t count = 0;
  double median = 0, p99 = 0, max = 0;  // s
};

// Nearest-rank percentiles of `seconds` (reordered in place).
LatencySummary summarise_latency(std::vector<double>& seconds);

// {"count", "median_ms", "p99_ms", "max_ms"}
nlohmann::json latency_json(const LatencySummary& s);

}  // namespace organsim
