#pragma once
// One row per case from its force log: OUTDIR/results.json and results.csv.
// Figures (pure functions of the case's scenario, equal in every rerun):
//   peak_force      N, the largest |F| over the samples, and peak_force_t (s)
//   force_at_<t>    N, |F| of the sample nearest t (null past the last sample)
//   dt_crit         s, the critical step the run estimated
//   completed, stop_reason, samples
// Timing (differs between reruns): real_time_factor, wall_seconds.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/sweep/sweep_plan.h"
#include "core/sweep/sweep_spec.h"

namespace organsim {

// Figures of one force log (forces.json as parsed); `at_times` in s.
nlohmann::json force_log_figures(const nlohmann::json& log, const std::vector<double>& at_times);

// "force_at_0.1" for t = 0.1: the column name of a force_at figure.
std::string force_at_name(double t);

// A figure's name with its unit for axis labels: "peak_force (N)".
std::string figure_label(const std::string& figure);

// One entry per case of the plan (with its record): name, status,
// overrides, figures, timing, error.
nlohmann::json results_json(const Sweep& plan, const std::vector<CaseRecord>& records,
                            const std::filesystem::path& outdir, const std::vector<double>& at_times);

// The same rows as CSV (RFC 4180 quoting): case, status, one column per
// swept field, the figures, the timing, error.
std::string results_csv(const Sweep& plan, const nlohmann::json& results, const std::vector<double>& at_times);

}  // namespace organsim
