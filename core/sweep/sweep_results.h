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

// What a results row takes from one force log.
struct ForceLogSummary {
  nlohmann::json figures;  // peak_force, peak_force_t, force_at_<t>, dt_crit, completed, stop_reason, samples
  nlohmann::json timing;   // real_time_factor, wall_seconds
};

// The figures and timing of one force log's text (forces.json as `organsim
// run` writes it); `at_times` in s. Throws Error(Input) naming `source` and
// the entry when it is not one: invalid JSON, meta or samples not objects,
// samples.t and samples.force not arrays of one length, a time that is not
// a number, a force that is not three numbers or nulls (null: not finite),
// a meta entry read here of another type.
ForceLogSummary force_log_summary(const std::string& text, const std::string& source,
                                  const std::vector<double>& at_times);
// The same for a log already parsed.
ForceLogSummary force_log_summary_json(const nlohmann::json& log, const std::string& source,
                                       const std::vector<double>& at_times);

// "force_at_0.1" for t = 0.1: the column name of a force_at figure.
std::string force_at_name(double t);

// A figure's name with its unit for axis labels: "peak_force (N)".
std::string figure_label(const std::string& figure);

// One entry per case of the plan (with its record): name, status,
// overrides, figures, timing, error. A done case's force log that is not
// one throws (force_log_summary); a failed case's leaves its figures null.
nlohmann::json results_json(const Sweep& plan, const std::vector<CaseRecord>& records,
                            const std::filesystem::path& outdir, const std::vector<double>& at_times);

// The same rows as CSV (RFC 4180 quoting): case, status, one column per
// swept field, the figures, the timing, error.
std::string results_csv(const Sweep& plan, const nlohmann::json& results, const std::vector<double>& at_times);

}  // namespace organsim
