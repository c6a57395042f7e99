// `organsim study SCENARIO.json --dt LIST --backend LIST --precision LIST [--jobs N] [-o OUTDIR]`
// Error against run time: runs the scenario once per configuration, compares
// each with a converged double-precision CPU reference and writes study.json,
// study.csv and study.png (error against wall time per simulated second,
// log-log, Pareto front marked). The haptic tick of the scenario is kept:
// each asked dt becomes tick / round(tick / dt). SI units.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "app/backend_factory.h"
#include "app/command.h"
#include "app/scenario_mesh.h"
#include "app/sweep_runner.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/stability/study.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

#ifdef ORGANSIM_STUDY_PLOT
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct StudyArgs {
  std::string scenario;
  std::string outdir;
  std::vector<double> dts;
  std::vector<std::string> backends{"cpu"};
  std::vector<std::string> precisions{"double", "float"};
  double duration = 0;           // s; 0 = the scenario's
  int32_t ref_factor = 4;        // reference dt = smallest asked dt / ref_factor
  double ref_tolerance = 1e-4;   // max position change from halving dt_ref, relative to the bbox diagonal
  int32_t samples = 50;          // position samples per run
  int32_t threads = 0;
  int32_t jobs = 1;              // configurations run at once
};

struct Outcome {
  std::string backend, precision, device;
  double dt = 0;
  int32_t substeps = 0;
  bool ran = false;        // false: the backend could not be created
  bool stable = false;
  std::string reason;      // why unstable or not run
  double simulated = 0;    // s
  double wall = 0;         // s, stepping loop
  double steps_per_second = 0;
  StudyErrors errors;
  Trajectory trajectory;
};

std::string fmt(double v, const char* spec = "%.4g") {
  char buf[64];
  std::snprintf(buf, sizeof buf, spec, v);
  return buf;
}

Outcome run_configuration(const Scenario& base, const Model& model, const std::string& backend_name,
                          const std::string& precision, int32_t substeps, int32_t threads, int64_t sample_every,
                          const PreparedRun& prepared) {
  Outcome o;
  o.backend = backend_name;
  o.precision = precision;
  Scenario s = base;
  s.time.substeps = substeps;
  s.time.dt = base.time.tick() / substeps;
  s.outputs = OutputsDef{};
  s.outputs.forces = false;
  o.dt = s.time.dt;
  o.substeps = substeps;
  BackendSelection selection;
  selection.name = backend_name;
  selection.precision = precision;
  selection.threads = threads;
  std::unique_ptr<Backend> backend;
  try {
    backend = make_backend(selection, model, backend_tool(s));
  } catch (const Error& e) {
    o.reason = e.what();
    return o;
  }
  prepared.start(*backend);  // the settled start
  o.ran = true;
  o.device = backend->device();
  o.trajectory.latency_ticks = backend->reaction_latency_ticks();
  // Every tick: when a configuration goes unstable is what the study reports.
  BlowupMonitor monitor = prepared.blowup_monitor(s, s.time.dt, 1);
  PositionSampler sampler(sample_every, o.trajectory);
  RunOptions options;
  options.observers = {&monitor, &sampler};
  const auto start = std::chrono::steady_clock::now();
  try {
    const RunResult r = run_scenario(s, model, *backend, options);
    o.stable = true;
    o.wall = r.meta.wall_seconds;
    o.steps_per_second = r.meta.steps_per_second;
    o.simulated = static_cast<double>(r.samples.size()) * s.time.tick();
    o.trajectory.force = r.samples.force;
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Numerical) throw;
    o.stable = false;
    o.reason = e.what();
    o.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return o;
}

nlohmann::json outcome_json(const Outcome& o, const StabilityReport& st, bool pareto) {
  nlohmann::json j = {{"backend", o.backend}, {"precision", o.precision}, {"dt", o.dt},
                      {"substeps", o.substeps}, {"dt_over_dt_crit", o.dt / st.dt_crit}, {"ran", o.ran}};
  if (!o.ran) {
    j["error"] = o.reason;
    return j;
  }
  j["device"] = o.device;
  j["stable"] = o.stable;
  j["reason"] = o.stable ? "completed; no blow-up detected" : o.reason;
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
void write_plot(const fs::path& path, const std::vector<Outcome>& runs, const std::vector<bool>& front) {
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
    cv::putText(img, "1e" + fmt(d, "%.0f"), {px(d) - 15, H - B + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  for (double d = y0; d <= y1 + 1e-9; d += 1) {
    cv::line(img, {L, py(d)}, {W - R, py(d)}, grey);
    cv::putText(img, "1e" + fmt(d, "%.0f"), {L - 45, py(d) + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black);
  }
  cv::rectangle(img, {L, T}, {W - R, H - B}, black);
  cv::putText(img, "wall time per simulated second [s]", {L + 120, H - 25}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  cv::putText(img, "RMS position error / bbox diagonal", {10, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.5, black);
  const cv::Scalar colours[] = {{200, 80, 30}, {30, 140, 230}, {60, 170, 60}, {160, 60, 200}};
  std::vector<std::string> series;
  auto series_of = [&](const Outcome& o) {
    const std::string name = o.backend + " " + o.precision;
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
    cv::putText(img, fmt(runs[i].dt, "%.2g"), p + cv::Point(7, -6), cv::FONT_HERSHEY_SIMPLEX, 0.35, c);
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

void progress(int done, int total, const std::string& what) {
  if (!isatty(2)) return;
  std::cerr << "\r[" << done << "/" << total << "] " << what << "                    " << std::flush;
  if (done == total) std::cerr << "\n";
}

// task(i) for i in [0, count) on up to `jobs` threads, each index once; after
// all have finished, the first exception (by index) is rethrown, so a
// failure reads the same as in a serial study.
void run_jobs(size_t count, int jobs, const std::function<void(size_t)>& task) {
  std::vector<std::exception_ptr> failed(count);
  std::atomic<size_t> next{0};
  const auto worker = [&] {
    for (size_t i = next++; i < count; i = next++) {
      try {
        task(i);
      } catch (...) {
        failed[i] = std::current_exception();
      }
    }
  };
  std::vector<std::thread> threads;
  for (int k = 1; k < std::min<int>(jobs, static_cast<int>(count)); ++k) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  for (const std::exception_ptr& e : failed)
    if (e) std::rethrow_exception(e);
}

void study_command(const StudyArgs& args) {
  Scenario s = load_scenario(args.scenario);
  if (args.duration > 0) s.time.duration = args.duration;
  const TetMesh mesh = load_scenario_mesh(s.mesh);
  const Model model = build_scenario_model(s, mesh);
  // Every configuration, the reference included, starts from the scenario's
  // start at rest (time.settle), so the study compares only what the tool does.
  const PreparedRun prepared = prepare_run(s, model, {true, args.threads});
  const StabilityReport& stability = prepared.stability;
  const double tick = s.time.tick();
  Vec3 lo = model.rest_position[0], hi = lo;
  for (const Vec3& p : model.rest_position) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const double diag = (hi - lo).norm();
  const int64_t sample_every = std::max<int64_t>(1, s.time.ticks() / std::max(args.samples, 1));

  std::vector<int32_t> substeps;
  for (double dt : args.dts) {
    if (!(dt > 0)) throw Error(ErrorKind::Usage, "--dt: expected positive steps in s, got " + fmt(dt));
    substeps.push_back(std::max<int32_t>(1, static_cast<int32_t>(std::lround(tick / dt))));
  }
  const int32_t finest = *std::max_element(substeps.begin(), substeps.end());
  const int32_t ref_substeps = finest * args.ref_factor;
  const int total = 2 + static_cast<int>(substeps.size() * args.backends.size() * args.precisions.size());
  int done = 0;
  // With --jobs N the runs share the CPUs: each gets its share of threads
  // (results do not depend on the thread count, so they equal a serial
  // study's; run times do, which is why one job is the default).
  const int32_t threads = args.threads > 0 || args.jobs <= 1 ? args.threads : std::max(1, usable_cpus() / args.jobs);
  std::mutex progress_mutex, gl_mutex;
  const auto step = [&](const std::string& what) {
    const std::lock_guard<std::mutex> lock(progress_mutex);
    progress(++done, total, what);
  };

  // The converged reference: double CPU at dt_ref and dt_ref / 2.
  progress(done, total, "reference dt " + fmt(tick / ref_substeps) + " and " + fmt(tick / (2 * ref_substeps)));
  Outcome ref, half;
  run_jobs(2, args.jobs, [&](size_t i) {
    Outcome& o = i == 0 ? ref : half;
    o = run_configuration(s, model, "cpu", "double", static_cast<int32_t>(i + 1) * ref_substeps, threads, sample_every,
                          prepared);
    step("reference dt " + fmt(o.dt));
  });
  if (!ref.stable || !half.stable)
    throw Error(ErrorKind::Numerical, "study reference (cpu double, dt " + fmt(half.dt) +
                                          " s) did not complete: " + (half.stable ? ref.reason : half.reason));
  const StudyErrors convergence = compare_trajectories(ref.trajectory, half.trajectory, diag);
  const bool converged = convergence.position_max <= args.ref_tolerance;
  if (!converged)
    std::cerr << "organsim: warning: the reference is not converged: halving dt_ref changed positions by "
              << fmt(convergence.position_max) << " of the bbox diagonal (tolerance " << fmt(args.ref_tolerance)
              << "); use a larger --ref-factor\n";

  struct Configuration {
    std::string backend, precision;
    int32_t substeps = 0;
  };
  std::vector<Configuration> configurations;
  for (const std::string& b : args.backends)
    for (const std::string& p : args.precisions)
      for (int32_t n : substeps) configurations.push_back({b, p, n});
  std::vector<Outcome> runs(configurations.size());
  run_jobs(configurations.size(), args.jobs, [&](size_t i) {
    const Configuration& c = configurations[i];
    // GL runs one at a time: each holds its own context, and they would
    // share one device.
    std::unique_lock<std::mutex> gl_lock(gl_mutex, std::defer_lock);
    if (c.backend == "gl") gl_lock.lock();
    Outcome o = run_configuration(s, model, c.backend, c.precision, c.substeps, threads, sample_every, prepared);
    if (o.stable) o.errors = compare_trajectories(o.trajectory, half.trajectory, diag);
    o.trajectory = Trajectory{};  // keep memory flat
    runs[i] = std::move(o);
    step(c.backend + " " + c.precision + " dt " + fmt(tick / c.substeps));
  });

  std::vector<double> cost, error;
  for (const Outcome& o : runs) {
    const bool ok = o.ran && o.stable;
    cost.push_back(ok ? o.wall / o.simulated : NAN);
    error.push_back(ok ? o.errors.position_rms : NAN);
  }
  const std::vector<bool> front = pareto_front(cost, error);

  const fs::path outdir = args.outdir.empty() ? fs::path("out") / (fs::path(args.scenario).stem().string() + "_study")
                                              : fs::path(args.outdir);
  fs::create_directories(outdir);
  nlohmann::json j;
  j["scenario"] = args.scenario;
  j["units"] = "SI: dt s, wall time per simulated second s/s; errors relative (positions to the bbox diagonal, "
               "forces to the reference's peak)";
  j["model"] = {{"points", model.npoint()}, {"springs", model.nspring()}, {"tets", model.ntet()},
                {"bbox_diagonal", diag}};
  j["tick"] = tick;
  j["duration"] = s.time.duration;
  j["step_policy"] = "the haptic tick is kept: each asked dt becomes tick / round(tick / dt)";
  j["stability"] = to_json(stability);
  j["reference"] = {{"backend", "cpu"}, {"precision", "double"}, {"dt", ref.dt}, {"dt_half", half.dt},
                    {"compared_against", "dt_half"},
                    {"halving_position_change_max", convergence.position_max},
                    {"halving_position_change_rms", convergence.position_rms},
                    {"halving_force_change_rms", convergence.force_rms},
                    {"tolerance", args.ref_tolerance}, {"converged", converged}};
  j["runs"] = nlohmann::json::array();
  for (size_t i = 0; i < runs.size(); ++i) j["runs"].push_back(outcome_json(runs[i], stability, front[i]));
  write_file_atomically(outdir / "study.json", [&](std::ostream& out) { out << j.dump(2) << "\n"; });

  std::ostringstream csv;
  csv << "backend,precision,dt_s,substeps,dt_over_dt_crit,stable,wall_s_per_sim_s,steps_per_s,"
         "position_error_max,position_error_rms,force_error_rms,pareto,reason\n";
  for (size_t i = 0; i < runs.size(); ++i) {
    const Outcome& o = runs[i];
    std::string reason = o.stable ? "" : o.reason;
    std::replace(reason.begin(), reason.end(), '"', '\'');
    csv << o.backend << "," << o.precision << "," << fmt(o.dt, "%.6g") << "," << o.substeps << ","
        << fmt(o.dt / stability.dt_crit, "%.3f") << "," << (o.ran ? (o.stable ? "yes" : "no") : "not run") << ",";
    if (o.stable)
      csv << fmt(o.wall / o.simulated) << "," << fmt(o.steps_per_second) << "," << fmt(o.errors.position_max) << ","
          << fmt(o.errors.position_rms) << "," << fmt(o.errors.force_rms) << "," << (front[i] ? "yes" : "no");
    else
      csv << ",,,,,";
    csv << ",\"" << reason << "\"\n";
  }
  write_file_atomically(outdir / "study.csv", [&](std::ostream& out) { out << csv.str(); });

  std::cout << "reference: cpu double dt " << fmt(half.dt) << " s; halving dt_ref changed positions by "
            << fmt(convergence.position_max) << " (max) of the bbox diagonal: "
            << (converged ? "converged" : "NOT converged") << "\n";
  std::cout << "dt_crit " << fmt(stability.dt_crit) << " s\n";
  std::cout << csv.str();
#ifdef ORGANSIM_STUDY_PLOT
  write_plot(outdir / "study.png", runs, front);
  std::cout << "study: " << (outdir / "study.json").string() << ", study.csv, study.png\n";
#else
  throw Error(ErrorKind::Output, (outdir / "study.png").string() +
                                     ": not written, this build has no OpenCV (study.json and study.csv are there)");
#endif
}

const bool registered = register_command("study", 40, [](CLI::App& root) {
  auto args = std::make_shared<StudyArgs>();
  CLI::App* cmd = root.add_subcommand(
      "study", "Error against run time: run a scenario at several dt [s], backends and precisions, compare each "
               "with a converged double-precision CPU reference, write study.json, study.csv and study.png");
  cmd->add_option("scenario", args->scenario, "Scenario file (see docs/scenarios.md)")->required();
  cmd->add_option("--dt", args->dts, "Integration steps to try, s (comma-separated); the tick is kept")
      ->required()
      ->delimiter(',');
  cmd->add_option("--backend", args->backends, "Backends (comma-separated: cpu, gl)")->delimiter(',');
  cmd->add_option("--precision", args->precisions, "Precisions (comma-separated: double, float)")->delimiter(',');
  cmd->add_option("-o,--output", args->outdir, "Output folder (default: out/<scenario name>_study)");
  cmd->add_option("--duration", args->duration, "Simulated time per run, s (default: the scenario's)");
  cmd->add_option("--ref-factor", args->ref_factor, "Reference dt = smallest asked dt / this (default 4)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ref-tolerance", args->ref_tolerance,
                  "Largest position change from halving the reference dt, relative to the bbox diagonal (default 1e-4)");
  cmd->add_option("--samples", args->samples, "Position samples per run (default 50)")->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads,
                  "CPU threads per run (0: all, or with --jobs the CPUs shared among the jobs)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--jobs", args->jobs,
                  "Configurations run at once (default 1: the wall times are the study's cost axis, and runs "
                  "side by side slow each other; the errors are the same)")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] { study_command(*args); });
});

}  // namespace
}  // namespace organsim::app
