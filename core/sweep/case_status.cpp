#include "core/sweep/case_status.h"

#include <cmath>
#include <csignal>
#include <cstring>
#include <sstream>

#include "core/sweep/sweep_results.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/json_fields.h"

namespace organsim {

namespace fs = std::filesystem;

const char* to_string(CaseState s) {
  switch (s) {
    case CaseState::Done:
      return "done";
    case CaseState::Failed:
      return "failed";
    default:
      return "pending";
  }
}

nlohmann::json to_json(const CaseStatus& s) {
  return {
      {"status", to_string(s.state)},   {"exit_code", s.exit_code},         {"signal", s.signal}, {"error", s.error},
      {"wall_seconds", s.wall_seconds}, {"scenario_hash", s.scenario_hash}, {"meta", s.meta}};
}

std::optional<CaseStatus> parse_case_status(const std::string& text) {
  const JsonFields r("status.json");
  try {
    const nlohmann::json j = r.parse(text);
    CaseStatus s;
    const std::string state = r.text(j, "status", "file");
    if (state != "done" && state != "failed") return std::nullopt;
    s.state = state == "done" ? CaseState::Done : CaseState::Failed;
    s.exit_code = static_cast<int>(r.whole(j, "exit_code", "file", -(1 << 30), 1 << 30));
    s.signal = static_cast<int>(r.whole(j, "signal", "file", 0, 1 << 30));
    s.error = r.text(j, "error", "file");
    s.wall_seconds = r.number(j, "wall_seconds", "file");
    if (!(s.wall_seconds >= 0 && std::isfinite(s.wall_seconds))) return std::nullopt;
    s.scenario_hash = r.text(j, "scenario_hash", "file");
    s.meta = r.field(j, "meta", "file");
    return s;
  } catch (const Error&) {
    return std::nullopt;
  }
}

std::optional<CaseStatus> read_case_status(const fs::path& case_dir) {
  const fs::path path = case_dir / "status.json";
  if (!fs::exists(path)) return std::nullopt;
  try {
    return parse_case_status(read_text_file(path));
  } catch (const Error&) {  // unreadable (a folder, no permission)
    return std::nullopt;
  }
}

void write_case_status(const fs::path& case_dir, const CaseStatus& s) {
  const std::string text = to_json(s).dump(2);
  write_file_atomically(case_dir / "status.json", [&](std::ostream& out) { out << text << "\n"; });
}

CaseState current_state(const SweepCase& c, const fs::path& case_dir) {
  const auto s = read_case_status(case_dir);
  if (!s || s->scenario_hash != c.scenario_hash) return CaseState::Pending;
  if (s->state == CaseState::Done && c.writes_forces && !fs::exists(case_dir / "forces.json"))
    return CaseState::Pending;
  return s->state;
}

namespace {

// The run's own message for the failure: its last "organsim: ... error"
// line, else its last non-empty line.
std::string last_error_line(const std::string& log_text) {
  std::istringstream in(log_text);
  std::string line, last, last_error;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    last = line;
    if (line.rfind("organsim: ", 0) == 0 && line.find("error") != std::string::npos) last_error = line;
  }
  return last_error.empty() ? last : last_error;
}

nlohmann::json meta_summary(const nlohmann::json& meta) {
  nlohmann::json s = nlohmann::json::object();
  for (const char* key : {"backend", "device", "precision", "points", "springs", "tets", "dt", "substeps", "samples",
                          "completed", "stop_reason", "wall_seconds", "real_time_factor", "dt_crit"}) {
    if (meta.contains(key)) s[key] = meta[key];
  }
  return s;
}

}  // namespace

CaseStatus judge_run(const SweepCase& c, const fs::path& case_dir, int exit_code, int signal, double wall_seconds,
                     const std::string& log_text) {
  CaseStatus s;
  s.exit_code = exit_code;
  s.signal = signal;
  s.wall_seconds = wall_seconds;
  s.scenario_hash = c.scenario_hash;
  std::string log_problem;
  const fs::path log_path = case_dir / "forces.json";
  if (fs::exists(log_path)) {
    // Read as --collect reads it: a log it would refuse is no complete log.
    try {
      const std::string source = "forces.json";
      const nlohmann::json log = JsonFields(source).parse(read_text_file(log_path));
      const ForceLogSummary summary = force_log_summary_json(log, source, {});
      s.meta = meta_summary(log.at("meta"));
      const std::string reason = summary.figures["stop_reason"];
      if (!summary.figures["completed"].get<bool>())
        log_problem = "forces.json: the run stopped early: " + (reason.empty() ? std::string("?") : reason);
    } catch (const Error& e) {
      log_problem = e.what();
    }
  } else if (c.writes_forces) {
    log_problem = "forces.json was not written";
  }
  if (exit_code == 0 && signal == 0 && log_problem.empty()) {
    s.state = CaseState::Done;
    return s;
  }
  s.state = CaseState::Failed;
  if (signal != 0)
    s.error = "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  else if (exit_code != 0)
    s.error = last_error_line(log_text);
  else
    s.error = "exited 0, but " + log_problem;
  return s;
}

}  // namespace organsim
