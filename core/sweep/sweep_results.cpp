#include "core/sweep/sweep_results.h"

#include <cmath>
#include <limits>

#include "core/sweep/sweep_plan.h"
#include "core/util/atomic_file.h"

namespace organsim {

namespace fs = std::filesystem;

std::string force_at_name(double t) { return "force_at_" + nlohmann::json(t).dump(); }

std::string figure_label(const std::string& figure) {
  if (figure == "peak_force" || figure.rfind("force_at_", 0) == 0) return figure + " (N)";
  if (figure == "peak_force_t" || figure == "dt_crit" || figure == "wall_seconds") return figure + " (s)";
  return figure;
}

nlohmann::json force_log_figures(const nlohmann::json& log, const std::vector<double>& at_times) {
  const nlohmann::json& meta = log.at("meta");
  const nlohmann::json& t = log.at("samples").at("t");
  const nlohmann::json& force = log.at("samples").at("force");
  auto magnitude = [&](size_t i) -> double {
    const auto& f = force[i];
    if (f[0].is_null() || f[1].is_null() || f[2].is_null()) return std::numeric_limits<double>::quiet_NaN();
    return std::sqrt(f[0].get<double>() * f[0].get<double>() + f[1].get<double>() * f[1].get<double>() +
                     f[2].get<double>() * f[2].get<double>());
  };
  nlohmann::json fig = nlohmann::json::object();
  double peak = 0, peak_t = 0;
  for (size_t i = 0; i < force.size(); ++i) {
    const double m = magnitude(i);
    if (m > peak) {
      peak = m;
      peak_t = t[i].get<double>();
    }
  }
  fig["peak_force"] = peak;
  fig["peak_force_t"] = peak_t;
  const double tick = meta.value("tick", 0.0);
  for (double at : at_times) {
    nlohmann::json value = nullptr;
    size_t best = force.size();
    for (size_t i = 0; i < force.size(); ++i) {
      if (best == force.size() || std::abs(t[i].get<double>() - at) < std::abs(t[best].get<double>() - at)) best = i;
    }
    // Nearest sample, unless the run stopped more than half a tick before t.
    if (best < force.size() && at <= t[best].get<double>() + 0.5 * tick) {
      const double m = magnitude(best);
      if (std::isfinite(m)) value = m;
    }
    fig[force_at_name(at)] = value;
  }
  fig["dt_crit"] = meta.contains("dt_crit") ? meta["dt_crit"] : nlohmann::json(nullptr);
  fig["completed"] = meta.value("completed", false);
  fig["stop_reason"] = meta.value("stop_reason", std::string());
  fig["samples"] = force.size();
  return fig;
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
      const nlohmann::json log = nlohmann::json::parse(read_text_file(log_path));
      row["figures"] = force_log_figures(log, at_times);
      row["timing"] = {{"real_time_factor", log["meta"].value("real_time_factor", 0.0)},
                       {"wall_seconds", log["meta"].value("wall_seconds", 0.0)}};
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
