#include "core/sweep/sweep_results.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/sweep/sweep_plan.h"
#include "core/util/atomic_file.h"
#include "core/util/json_fields.h"

namespace organsim {

namespace fs = std::filesystem;

std::string force_at_name(double t) { return "force_at_" + nlohmann::json(t).dump(); }

std::string figure_label(const std::string& figure) {
  if (figure == "peak_force" || figure.rfind("force_at_", 0) == 0) return figure + " (N)";
  if (figure == "peak_force_t" || figure == "dt_crit" || figure == "wall_seconds") return figure + " (s)";
  return figure;
}

namespace {

// The meta entry `name` when present and of the type `is` tests, `fallback` when absent.
template <class Test>
nlohmann::json meta_entry(const JsonFields& r, const nlohmann::json& meta, const char* name, Test is,
                          const char* expected, nlohmann::json fallback) {
  if (!meta.contains(name)) return fallback;
  const nlohmann::json& v = meta.at(name);
  if (!is(v)) throw r.error(std::string("meta.") + name, expected);
  return v;
}

}  // namespace

ForceLogSummary force_log_summary(const std::string& text, const std::string& source,
                                  const std::vector<double>& at_times) {
  return force_log_summary_json(JsonFields(source).parse(text), source, at_times);
}

ForceLogSummary force_log_summary_json(const nlohmann::json& log, const std::string& source,
                                       const std::vector<double>& at_times) {
  const JsonFields r(source);
  const nlohmann::json& meta = r.object(log, "meta", "file");
  const nlohmann::json& samples = r.object(log, "samples", "file");
  const nlohmann::json& tj = r.array(samples, "t", "samples");
  const nlohmann::json& fj = r.array(samples, "force", "samples");
  if (fj.size() != tj.size()) throw r.error("samples.force", "one force per time (" + std::to_string(tj.size()) + ")");
  const auto is_number = [](const nlohmann::json& v) { return v.is_number(); };
  const auto is_number_or_null = [](const nlohmann::json& v) { return v.is_number() || v.is_null(); };
  std::vector<double> t(tj.size()), magnitude(tj.size());
  for (size_t i = 0; i < t.size(); ++i) {
    const std::string index = std::to_string(i);
    if (!tj[i].is_number()) throw r.error("samples.t[" + index + "]", "a time in s");
    t[i] = tj[i].get<double>();
    const nlohmann::json& f = fj[i];
    if (!f.is_array() || f.size() != 3 || !std::all_of(f.begin(), f.end(), is_number_or_null))
      throw r.error("samples.force[" + index + "]", "three numbers or nulls (N)");
    magnitude[i] = f[0].is_null() || f[1].is_null() || f[2].is_null()
                       ? std::numeric_limits<double>::quiet_NaN()
                       : std::sqrt(f[0].get<double>() * f[0].get<double>() + f[1].get<double>() * f[1].get<double>() +
                                   f[2].get<double>() * f[2].get<double>());
  }
  const double tick = meta_entry(r, meta, "tick", is_number, "a tick in s", 0.0).get<double>();

  ForceLogSummary s;
  nlohmann::json& fig = s.figures = nlohmann::json::object();
  double peak = 0, peak_t = 0;
  for (size_t i = 0; i < t.size(); ++i) {
    if (magnitude[i] > peak) {
      peak = magnitude[i];
      peak_t = t[i];
    }
  }
  fig["peak_force"] = peak;
  fig["peak_force_t"] = peak_t;
  for (double at : at_times) {
    nlohmann::json value = nullptr;
    size_t best = t.size();
    for (size_t i = 0; i < t.size(); ++i) {
      if (best == t.size() || std::abs(t[i] - at) < std::abs(t[best] - at)) best = i;
    }
    // Nearest sample, unless the run stopped more than half a tick before t.
    if (best < t.size() && at <= t[best] + 0.5 * tick && std::isfinite(magnitude[best])) value = magnitude[best];
    fig[force_at_name(at)] = value;
  }
  fig["dt_crit"] = meta_entry(r, meta, "dt_crit", is_number_or_null, "a step in s or null", nullptr);
  fig["completed"] = meta_entry(
      r, meta, "completed", [](const nlohmann::json& v) { return v.is_boolean(); }, "true or false", false);
  fig["stop_reason"] = meta_entry(
      r, meta, "stop_reason", [](const nlohmann::json& v) { return v.is_string(); }, "a string", "");
  fig["samples"] = t.size();
  s.timing = {{"real_time_factor", meta_entry(r, meta, "real_time_factor", is_number, "a number", 0.0)},
              {"wall_seconds", meta_entry(r, meta, "wall_seconds", is_number, "a time in s", 0.0)}};
  return s;
}

nlohmann::json results_json(const Sweep& plan, const std::vector<CaseRecord>& records, const fs::path& outdir,
                            const std::vector<double>& at_times) {
  const nlohmann::json manifest = manifest_json(plan, records);
  nlohmann::json rows = nlohmann::json::array();
  for (size_t i = 0; i < plan.cases.size(); ++i) {
    const SweepCase& c = plan.cases[i];
    const nlohmann::json& m = manifest["cases"][i];
    nlohmann::json row = {{"name", c.name},     {"status", m["status"]}, {"overrides", m["overrides"]},
                          {"figures", nullptr}, {"timing", nullptr},     {"error", m.value("error", std::string())}};
    const fs::path log_path = case_dir(outdir, c) / "forces.json";
    if (m["status"] != "pending" && fs::exists(log_path)) {
      try {
        ForceLogSummary log = force_log_summary(read_text_file(log_path), log_path.string(), at_times);
        row["figures"] = std::move(log.figures);
        row["timing"] = std::move(log.timing);
      } catch (const Error&) {
        // A failed case's log may be why it failed (judge_run), and its row
        // says so; a done case's log was read when it was judged: it changed since.
        if (m["status"] == "done") throw;
      }
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

namespace {

std::string csv_field(const nlohmann::json& v) {
  if (v.is_null()) return "";
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string quoted = "\"";
  for (char c : s) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string csv_line(const std::vector<std::string>& cells) {
  std::string line;
  for (size_t i = 0; i < cells.size(); ++i) {
    if (i) line += ',';
    line += cells[i];
  }
  line += '\n';
  return line;
}

}  // namespace

std::string results_csv(const Sweep& plan, const nlohmann::json& results, const std::vector<double>& at_times) {
  std::vector<std::string> figures{"peak_force", "peak_force_t"};
  for (double t : at_times) figures.push_back(force_at_name(t));
  for (const char* f : {"dt_crit", "completed", "stop_reason", "samples"}) figures.push_back(f);
  const std::vector<std::string> timing{"real_time_factor", "wall_seconds"};

  std::vector<std::string> header{"case", "status"};
  for (const std::string& p : plan.swept_paths) header.push_back(csv_field(p));
  header.insert(header.end(), figures.begin(), figures.end());
  header.insert(header.end(), timing.begin(), timing.end());
  header.push_back("error");
  std::string out = csv_line(header);
  for (const nlohmann::json& row : results) {
    std::vector<std::string> cells{csv_field(row["name"]), csv_field(row["status"])};
    for (const std::string& p : plan.swept_paths)
      cells.push_back(row["overrides"].contains(p) ? csv_field(row["overrides"][p]) : std::string());
    for (const std::string& f : figures)
      cells.push_back(row["figures"].is_null() ? std::string() : csv_field(row["figures"][f]));
    for (const std::string& f : timing)
      cells.push_back(row["timing"].is_null() ? std::string() : csv_field(row["timing"][f]));
    cells.push_back(csv_field(row["error"]));
    out += csv_line(cells);
  }
  return out;
}

}  // namespace organsim
