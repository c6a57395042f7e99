#include "app/sweep_collect.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>

#include "core/render/xy_plot.h"
#include "core/sweep/case_names.h"
#include "core/sweep/sweep_results.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim::app {

namespace {

namespace fs = std::filesystem;

bool all_numbers(const nlohmann::json& rows, const std::string& path) {
  for (const auto& row : rows) {
    if (!row["overrides"].contains(path) || !row["overrides"][path].is_number()) return false;
  }
  return true;
}

// y against one swept field; one line per combination of the other swept
// values, so a grid draws as a family of curves.
void write_results_plot(const fs::path& path, const Sweep& plan, const nlohmann::json& rows, const CollectOptions& o) {
  std::string x = o.plot_x;
  if (x.empty()) {
    for (const std::string& p : plan.swept_paths) {
      if (all_numbers(rows, p)) {
        x = p;
        break;
      }
    }
    if (x.empty()) {
      std::cout << "plot:     none (no swept field has numbers only; choose one with --plot-x)\n";
      return;
    }
  }
  if (std::find(plan.swept_paths.begin(), plan.swept_paths.end(), x) == plan.swept_paths.end())
    throw Error(ErrorKind::Usage,
                "--plot-x " + x + ": not a swept field of this sweep (" + plan.swept_paths.front() + ", ...)");
  if (!all_numbers(rows, x)) throw Error(ErrorKind::Usage, "--plot-x " + x + ": its values are not all numbers");
  const std::vector<std::string> labels = field_labels(plan.swept_paths);
  std::map<std::string, XySeries> series;
  for (const auto& row : rows) {
    const nlohmann::json* y = nullptr;
    if (row["figures"].is_object() && row["figures"].contains(o.plot_y)) y = &row["figures"][o.plot_y];
    if (row["timing"].is_object() && row["timing"].contains(o.plot_y)) y = &row["timing"][o.plot_y];
    if (!row["figures"].is_object()) continue;  // pending or failed without a log
    if (!y)
      throw Error(ErrorKind::Usage,
                  "--plot-y " + o.plot_y +
                      ": not a figure of the results (peak_force, force_at_<t>, dt_crit, real_time_factor, ...)");
    if (!y->is_number()) continue;
    std::string key;
    for (size_t i = 0; i < plan.swept_paths.size(); ++i) {
      const std::string& p = plan.swept_paths[i];
      if (p == x || !row["overrides"].contains(p)) continue;
      if (!key.empty()) key += ',';
      key.append(labels[i]).append("=").append(value_text(row["overrides"][p]));
    }
    XySeries& s = series[key];
    s.name = key.empty() ? o.plot_y : key;
    s.x.push_back(row["overrides"][x].get<double>());
    s.y.push_back(y->get<double>());
  }
  std::vector<XySeries> lines;
  for (auto& [key, s] : series) {
    std::vector<size_t> order(s.x.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return s.x[a] < s.x[b]; });
    XySeries sorted{s.name, {}, {}, true, true};
    for (size_t i : order) {
      sorted.x.push_back(s.x[i]);
      sorted.y.push_back(s.y[i]);
    }
    lines.push_back(std::move(sorted));
  }
  if (lines.empty()) {
    std::cout << "plot:     none (no case has " << o.plot_y << " yet)\n";
    return;
  }
  XyPlotOptions plot;
  plot.title = o.plot_y + " against " + x;
  plot.x_label = x;
  plot.y_label = figure_label(o.plot_y);
  write_xy_plot(path, lines, plot);
  std::cout << "plot:     " << path.string() << " (" << plot.title << ")\n";
}

}  // namespace

ManifestCounts collect_sweep(const fs::path& outdir, const CollectOptions& options) {
  const Sweep plan = read_plan(outdir);
  const std::vector<CaseRecord> records = read_case_records(plan, outdir);
  // Every force log read before anything is written: a log that is not one
  // stops the collection with the files of the last one intact.
  const nlohmann::json rows = results_json(plan, records, outdir, options.at_times);
  ManifestCounts counts;
  write_manifest(plan, records, outdir, &counts);
  const std::string json_text = rows.dump(2) + "\n";
  write_file_atomically(outdir / "results.json", [&](std::ostream& out) { out << json_text; });
  const std::string csv = results_csv(plan, rows, options.at_times);
  write_file_atomically(outdir / "results.csv", [&](std::ostream& out) { out << csv; });
  std::cout << "results:  " << (outdir / "results.csv").string() << ", results.json, manifest.json: " << counts.done
            << " done, " << counts.failed << " failed, " << counts.pending << " pending of " << plan.cases.size()
            << " cases\n";
  write_results_plot(outdir / "results.png", plan, rows, options);
  return counts;
}

}  // namespace organsim::app
