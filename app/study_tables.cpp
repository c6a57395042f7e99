#include "app/study_tables.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/format.h"

#ifdef ORGANSIM_STUDY_PLOT
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

nlohmann::json outcome_json(const StudyOutcome& o, double dt_crit, bool pareto) {
  nlohmann::json j = {{"integrator", o.integrator}, {"backend", o.backend}, {"precision", o.precision}, {"dt", o.dt},
                      {"substeps", o.substeps}, {"dt_over_dt_crit", o.dt / dt_crit}, {"ran", o.ran}};
  if (!o.ran) {
    j["error"] = o.reason;
    return j;
  }
  j["device"] = o.device;
  j["stable"] = o.stable;
  // A stable run's reason is empty, or the implicit solver's warning.
  j["reason"] = o.stable && o.reason.empty() ? "completed; no blow-up detected" : o.reason;
  if (o.stable) {
    j["wall_seconds_per_simulated_second"] = o.wall / o.simulated;
    j["steps_per_second"] = o.steps_per_second;
    j["position_error_max"] = o.errors.position_max;
    j["position_error_rms"] = o.errors.position_rms;
    j["force_error_rms"] = o.errors.force_rms;
    j["pareto"] = pareto;
  }
  return j;
}

#ifdef ORGANSIM_STUDY_PLOT
// Log-log scatter of RMS position error against wall time per simulated
// second; Pareto-front points joined and ringed. A small plot of our own so
// core stays free of OpenCV.
void write_plot(const fs::path& path, const std::vector<StudyOutcome>& runs, const std::vector<bool>& front) {
  const int W = 900, H = 600, L = 90, R = 250, T = 50, B = 70;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<size_t> idx;
  for (size_t i = 0; i < runs.size(); ++i)
    if (runs[i].ran && runs[i].stable && runs[i].errors.position_rms > 0) idx.push_back(i);
  auto cost = [&](size_t i) { return runs[i].wall / runs[i].simulated; };
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (size_t i : idx) {
    x0 = std::min(x0, std::log10(cost(i)));
    x1 = std::max(x1, std::log10(cost(i)));
    y0 = std::min(y0, std::log10(runs[i].errors.position_rms));
    y1 = std::max(y1, std::log10(runs[i].errors.position_rms));
  }
  if (idx.empty()) x0 = y0 = -1, x1 = y1 = 0;
  x0 = std::floor(x0), x1 = std::max(std::ceil(x1), x0 + 1), y0 = std::floor(y0), y1 = std::max(std::ceil(y1), y0 + 1);
  auto px = [&](double lx) { return L + static_cast<int>((lx - x0) / (x1 - x0) * (W - L - R)); };
  auto py = [&](double ly) { return H - B - static_cast<int>((ly - y0) / (y1 - y0) * (H - T - B)); };
  const cv::Scalar black(0, 0, 0), grey(210, 210, 210);
  for (double d = x0; d <= x1 + 1e-9; d += 1) {
    cv::line(img, {px(d), T}, {px(d), H - B}, grey);
    cv::putText(img, "1e" + format_number(d, "%.0f"), {px(d) - 15, H - B + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  for (double d = y0; d <= y1 + 1e-9; d += 1) {
    cv::line(img, {L, py(d)}, {W - R, py(d)}, grey);
    cv::putText(img, "1e" + format_number(d, "%.0f"), {L - 45, py(d) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black);
  cv::putText(img, "wall time per simulated second [s]", {L + 120, H - 25}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  cv::putText(img, "RMS position error / bbox diagonal", {10, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  const cv::Scalar colours[] = {{200, 80, 30}, {30, 140, 230}, {60, 170, 60}, {160, 60, 200}};
  std::vector<std::string> series;
  auto series_of = [&](const StudyOutcome& o) {
    const std::string name = (o.integrator == "verlet" ? "" : o.integrator + " ") + o.backend + " " + o.precision;
    auto it = std::find(series.begin(), series.end(), name);
    if (it == series.end()) {
      series.push_back(name);
      return series.size() - 1;
    }
    return static_cast<size_t>(it - series.begin());
  };
  std::vector<std::pair<double, size_t>> on_front;
  for (size_t i : idx) {
    const cv::Point p(px(std::log10(cost(i))), py(std::log10(runs[i].errors.position_rms)));
    const cv::Scalar c = colours[series_of(runs[i]) % 4];
    cv::circle(img, p, 5, c, cv::FILLED);
    cv::putText(img, format_number(runs[i].dt, "%.2g"), p + cv::Point(7, -6), cv::FONT_HERSHEY_SIMPLEX, 0.35, c);
    if (front[i]) {
      cv::circle(img, p, 10, black, 2);
      on_front.push_back({cost(i), i});
    }
  }
  std::sort(on_front.begin(), on_front.end());
  for (size_t k = 1; k < on_front.size(); ++k) {
    const size_t a = on_front[k - 1].second, b = on_front[k].second;
    cv::line(img, {px(std::log10(cost(a))), py(std::log10(runs[a].errors.position_rms))},
             {px(std::log10(cost(b))), py(std::log10(runs[b].errors.position_rms))}, black, 1, cv::LINE_AA);
  }
  for (size_t k = 0; k < series.size(); ++k) {
    cv::circle(img, {W - R + 25, T + 20 + 25 * static_cast<int>(k)}, 5, colours[k % 4], cv::FILLED);
    cv::putText(img, series[k], {W - R + 40, T + 25 + 25 * static_cast<int>(k)}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  }
  const int ly = T + 25 + 25 * static_cast<int>(series.size());
  cv::circle(img, {W - R + 25, ly - 5}, 10, black, 2);
  cv::putText(img, "Pareto front", {W - R + 40, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  cv::putText(img, "labels: dt [s]", {W - R + 20, ly + 25}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  std::vector<uchar> png;
  if (!cv::imencode(".png", img, png)) throw Error(ErrorKind::Output, path.string() + ": PNG encoding failed");
  write_file_atomically(path, [&](std::ostream& out) { out.write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size())); });
}
#endif

}  // namespace

void write_study_outputs(const fs::path& outdir, const nlohmann::json& head, double dt_crit,
                         const std::vector<StudyOutcome>& runs) {
  std::vector<double> cost, error;
  for (const StudyOutcome& o : runs) {
    const bool ok = o.ran && o.stable;
    cost.push_back(ok ? o.wall / o.simulated : NAN);
    error.push_back(ok ? o.errors.position_rms : NAN);
  }
  const std::vector<bool> front = pareto_front(cost, error);

  fs::create_directories(outdir);
  nlohmann::json j = head;
  j["runs"] = nlohmann::json::array();
  for (size_t i = 0; i < runs.size(); ++i) j["runs"].push_back(outcome_json(runs[i], dt_crit, front[i]));
  write_file_atomically(outdir / "study.json", [&](std::ostream& out) { out << j.dump(2) << "\n"; });

  std::ostringstream csv;
  csv << "integrator,backend,precision,dt_s,substeps,dt_over_dt_crit,stable,wall_s_per_sim_s,steps_per_s,"
         "position_error_max,position_error_rms,force_error_rms,pareto,reason\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    const StudyOutcome& o = runs[i];
    std::string reason = o.reason;
    std::replace(reason.begin(), reason.end(), '"', '\'');
    csv << o.integrator << "," << o.backend << "," << o.precision << "," << format_number(o.dt, "%.6g") << ","
        << o.substeps << "," << format_number(o.dt / dt_crit, "%.3f") << ","
        << (o.ran ? (o.stable ? "yes" : "no") : "not run") << ",";
    if (o.stable)
      csv << format_number(o.wall / o.simulated) << "," << format_number(o.steps_per_second) << ","
          << format_number(o.errors.position_max) << "," << format_number(o.errors.position_rms) << ","
          << format_number(o.errors.force_rms) << "," << (front[i] ? "yes" : "no");
    else
      csv << ",,,,,";
    csv << ",\"" << reason << "\"\n";
  }
  write_file_atomically(outdir / "study.csv", [&](std::ostream& out) { out << csv.str(); });

  const nlohmann::json& reference = head.at("reference");
  std::cout << "reference: verlet cpu double dt " << format_number(reference.at("dt_half").get<double>())
            << " s; halving dt_ref changed positions by "
            << format_number(reference.at("halving_position_change_max").get<double>())
            << " (max) of the bbox diagonal: "
            << (reference.at("converged").get<bool>() ? "converged" : "NOT converged") << "\n";
  std::cout << "dt_crit " << format_number(dt_crit) << " s\n";
  std::cout << csv.str();
#ifdef ORGANSIM_STUDY_PLOT
  write_plot(outdir / "study.png", runs, front);
  std::cout << "study: " << (outdir / "study.json").string() << ", study.csv, study.png\n";
#else
  throw Error(ErrorKind::Output, (outdir / "study.png").string() +
                                     ": not written, this build has no OpenCV (study.json and study.csv are there)");
#endif
}

}  // namespace organsim::app
