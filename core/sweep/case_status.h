#pragma once
// What is known about one case: OUTDIR/cases/<name>/status.json, written
// atomically by the sweep process after the case's run exited. It is the
// record that every other view (manifest.json, results) is built from, so
// several processes (shards, Slurm tasks) can share one output folder: each
// writes only the status files of its own cases.
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/sweep/sweep_spec.h"

namespace organsim {

enum class CaseState { Pending, Done, Failed };

const char* to_string(CaseState s);

struct CaseStatus {
  CaseState state = CaseState::Pending;
  int exit_code = 0;              // of `organsim run`; 0 when killed by a signal
  int signal = 0;                 // the signal that ended the run, 0 if it exited
  std::string error;              // the run's last error line; empty when done
  double wall_seconds = 0;        // s, the whole run process
  std::string scenario_hash;      // of the scenario that ran (SweepCase::scenario_hash)
  nlohmann::json meta = nullptr;  // summary of forces.json's meta (null without a log)
};

nlohmann::json to_json(const CaseStatus& s);

// A status file's text; nullopt unless it is one (valid JSON with every
// entry of to_json, of its type, the status "done" or "failed").
std::optional<CaseStatus> parse_case_status(const std::string& text);
// The status file of a case folder; nullopt when absent or not a status
// file (a case whose record cannot be read is simply run again).
std::optional<CaseStatus> read_case_status(const std::filesystem::path& case_dir);
void write_case_status(const std::filesystem::path& case_dir, const CaseStatus& s);

// The state of `c` in `case_dir` now: Pending unless its status file is
// there and was written for this very scenario text; Done only while the
// force log it promised is still there (it is written atomically, so there
// means complete).
CaseState current_state(const SweepCase& c, const std::filesystem::path& case_dir);

// Judges a finished run: Done only when it exited 0 and its force log (if
// the scenario asks for one) is complete (meta.completed). `log_text` is the
// run's output, whose last error line is kept for a failed case.
CaseStatus judge_run(const SweepCase& c, const std::filesystem::path& case_dir, int exit_code, int signal,
                     double wall_seconds, const std::string& log_text);

}  // namespace organsim
