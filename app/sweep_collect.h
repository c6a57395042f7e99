#pragma once
// `organsim sweep --collect OUTDIR`: manifest.json, results.json,
// results.csv and results.png from a sweep's output folder.
#include <filesystem>
#include <string>
#include <vector>

#include "core/sweep/sweep_plan.h"

namespace organsim::app {

struct CollectOptions {
  std::vector<double> at_times;  // s: a force_at_<t> figure for each
  std::string plot_x;            // swept field on x; empty: the first with numbers only
  std::string plot_y = "peak_force";
};

// Writes the four files and prints where they are; returns the counts.
ManifestCounts collect_sweep(const std::filesystem::path& outdir, const CollectOptions& options);

}  // namespace organsim::app
