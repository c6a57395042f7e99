// `organsim study SCENARIO.json --dt LIST --backend LIST --precision LIST [--integrator LIST
//  [--implicit-dt LIST]] [--jobs N] [-o OUTDIR]`
// `... --reference-only`, `... --shard i/N|slurm`, `organsim study --collect OUTDIR`
// Error against run time: runs the scenario once per configuration, compares
// each with a converged double-precision CPU reference and writes study.json,
// study.csv and study.png (error against wall time per simulated second,
// log-log, Pareto front marked). The haptic tick of the scenario is kept:
// each asked dt becomes tick / round(tick / dt). SI units. Sharded, the
// reference runs once (--reference-only) into files every shard reads
// (core/stability/study_files.h), and --collect writes the same table.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "app/backend_factory.h"
#include "app/command.h"
#include "app/scenario_mesh.h"
#include "app/study_tables.h"
#include "app/sweep_runner.h"
#include "core/run/integrator_report.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/stability/study.h"
#include "core/stability/study_files.h"
#include "core/sweep/shard.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct StudyArgs {
  std::string scenario;
  std::string outdir;
  std::vector<double> dts;
  std::vector<std::string> backends{"cpu"};
  std::vector<std::string> precisions{"double", "float"};
  // time.integrator names; an implicit one runs on the CPU in double only,
  // with the scenario's solver settings: implicit_euler at --implicit-dt,
  // implicit_damping at --damping-dt (each by default --dt).
  std::vector<std::string> integrators{"verlet"};
  std::vector<double> implicit_dts, damping_dts;
  double duration = 0;           // s; 0 = the scenario's
  int32_t ref_factor = 4;        // reference dt = smallest asked dt / ref_factor
  double ref_tolerance = 1e-4;   // max position change from halving dt_ref, relative to the bbox diagonal
  int32_t samples = 50;          // position samples per run
  int32_t threads = 0;
  int32_t jobs = 1;              // configurations run at once
  bool reference_only = false;   // write the reference and the plan for shards, run no configuration
  std::string shard;             // "i/N" or "slurm": run that slice against the written reference
  std::string collect;           // OUTDIR: the table from the shards' runs
};

// The files a sharded study shares in OUTDIR (core/stability/study_files.h).
fs::path plan_path(const fs::path& outdir) { return outdir / "study_plan.json"; }
fs::path reference_path(const fs::path& outdir) { return outdir / "study_reference.json"; }
fs::path runs_dir(const fs::path& outdir) { return outdir / "study_runs"; }
fs::path run_path(const fs::path& outdir, size_t k) { return runs_dir(outdir) / (std::to_string(k) + ".json"); }

// A configuration's outcome and, for comparison, its trajectory.
struct Ran {
  StudyOutcome outcome;
  Trajectory trajectory;
};

Integrator integrator_named(const std::string& name) {
  for (Integrator i : {Integrator::Verlet, Integrator::ImplicitEuler, Integrator::ImplicitDamping})
    if (name == integrator_name(i)) return i;
  throw Error(ErrorKind::Usage, "--integrator: expected verlet, implicit_euler or implicit_damping (got \"" + name + "\")");
}

Ran run_configuration(const Scenario& base, const Model& model, const StudyConfiguration& c, int32_t threads,
                      int64_t sample_every, const PreparedRun& prepared) {
  Ran ran;
  StudyOutcome& o = ran.outcome;
  Trajectory& trajectory = ran.trajectory;
  const std::string& backend_name = c.backend;
  const std::string& precision = c.precision;
  const int32_t substeps = c.substeps;
  o.integrator = c.integrator;
  o.backend = backend_name;
  o.precision = precision;
  Scenario s = base;
  s.time.integrator = integrator_named(c.integrator);
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
  selection.integrator = s.time.integrator;
  selection.implicit = s.time.implicit;
  std::unique_ptr<Backend> backend;
  try {
    backend = make_backend(selection, model, backend_tool(s));
  } catch (const Error& e) {
    o.reason = e.what();
    return ran;
  }
  prepared.start(*backend);  // the settled start
  o.ran = true;
  o.device = backend->device();
  trajectory.latency_ticks = backend->reaction_latency_ticks();
  // Every tick: when a configuration goes unstable is what the study reports.
  BlowupMonitor monitor = prepared.blowup_monitor(s, s.time.dt, 1);
  PositionSampler sampler(sample_every, trajectory);
  RunOptions options;
  options.observers = {&monitor, &sampler};
  const auto start = std::chrono::steady_clock::now();
  try {
    const RunResult r = run_scenario(s, model, *backend, options);
    o.stable = true;
    o.wall = r.meta.wall_seconds;
    o.steps_per_second = r.meta.steps_per_second;
    o.simulated = static_cast<double>(r.samples.size()) * s.time.tick();
    trajectory.force = r.samples.force;
    if (const std::string warning = integrator_warning(*backend); !warning.empty()) o.reason = warning;
  } catch (const Error& e) {
    if (e.kind() != ErrorKind::Numerical) throw;
    o.stable = false;
    o.reason = e.what();
    o.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return ran;
}

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


// What every run of a study shares: the scenario, its model, the settled
// start and the configurations in table order.
struct StudySetup {
  Scenario scenario;
  Model model;
  PreparedRun prepared;
  double diag = 0;              // m, the rest bounding box's diagonal
  int64_t sample_every = 1;     // ticks between position samples
  int32_t threads = 0;          // per run
  int32_t ref_substeps = 0;     // the reference's substeps; dt_ref / 2 takes twice as many
  std::vector<StudyConfiguration> configurations;
  nlohmann::json request;       // what a shard must share with the reference step
};

// Everything the runs' results depend on; the thread and job counts are not.
nlohmann::json request_of(const StudyArgs& args) {
  return {{"scenario_text", read_text_file(args.scenario)}, {"dt", args.dts}, {"backend", args.backends},
          {"precision", args.precisions}, {"duration", args.duration}, {"ref_factor", args.ref_factor},
          {"samples", args.samples}, {"integrator", args.integrators}, {"implicit_dt", args.implicit_dts},
          {"damping_dt", args.damping_dts}};
}

StudySetup set_up(const StudyArgs& args) {
  StudySetup u;
  u.scenario = load_scenario(args.scenario);
  Scenario& s = u.scenario;
  if (args.duration > 0) s.time.duration = args.duration;
  const TetMesh mesh = load_scenario_mesh(s.mesh);
  u.model = build_scenario_model(s, mesh);
  // Every configuration, the reference included, starts from the scenario's
  // start at rest (time.settle), so the study compares only what the tool does.
  u.prepared = prepare_run(s, u.model, {true, args.threads});
  Vec3 lo = u.model.rest_position[0], hi = lo;
  for (const Vec3& p : u.model.rest_position) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  u.diag = (hi - lo).norm();
  u.sample_every = std::max<int64_t>(1, s.time.ticks() / std::max(args.samples, 1));

  const double tick = s.time.tick();
  const auto substeps_of = [&](const std::vector<double>& dts, const char* option) {
    std::vector<int32_t> out;
    for (double dt : dts) {
      if (!(dt > 0))
        throw Error(ErrorKind::Usage, std::string(option) + ": expected positive steps in s, got " + format_number(dt));
      out.push_back(std::max<int32_t>(1, static_cast<int32_t>(std::lround(tick / dt))));
    }
    return out;
  };
  const std::vector<int32_t> substeps = substeps_of(args.dts, "--dt");
  const std::vector<int32_t> implicit_substeps =
      args.implicit_dts.empty() ? substeps : substeps_of(args.implicit_dts, "--implicit-dt");
  const std::vector<int32_t> damping_substeps =
      args.damping_dts.empty() ? substeps : substeps_of(args.damping_dts, "--damping-dt");
  int32_t most = 0;
  for (const std::string& name : args.integrators) {
    const Integrator integrator = integrator_named(name);
    if (!solves_implicitly(integrator)) {
      for (const std::string& b : args.backends)
        for (const std::string& p : args.precisions)
          for (int32_t n : substeps) u.configurations.push_back({b, p, n, name});
      continue;
    }
    // An implicit integrator runs on the CPU in double only: its rows are
    // those, and the other backends and precisions are not asked of it.
    for (int32_t n : integrator == Integrator::ImplicitEuler ? implicit_substeps : damping_substeps)
      u.configurations.push_back({"cpu", "double", n, name});
  }
  for (const StudyConfiguration& c : u.configurations) most = std::max(most, c.substeps);
  // The reference is Verlet, the integrator without numerical damping, at
  // a quarter of the smallest step asked of any integrator (and at half
  // that, to show it is converged): the solution of the same equations
  // every configuration approximates.
  u.ref_substeps = most * args.ref_factor;
  // With --jobs N the runs share the CPUs: each gets its share of threads
  // (results do not depend on the thread count, so they equal a serial
  // study's; run times do, which is why one job is the default).
  u.threads = args.threads > 0 || args.jobs <= 1 ? args.threads : std::max(1, usable_cpus() / args.jobs);
  u.request = request_of(args);
  return u;
}

Ran run_one(const StudySetup& u, const StudyConfiguration& c) {
  return run_configuration(u.scenario, u.model, c, u.threads, u.sample_every, u.prepared);
}

// The converged reference, double CPU at dt_ref and dt_ref / 2, and the head
// of study.json. Returns the dt_ref / 2 trajectory, the one compared with.
Trajectory run_reference(const StudyArgs& args, const StudySetup& u, nlohmann::json& head) {
  const double tick = u.scenario.time.tick();
  progress(
      0, 2,
      "reference dt " + format_number(tick / u.ref_substeps) + " and " + format_number(tick / (2 * u.ref_substeps)));
  Ran ref, half;
  std::mutex progress_mutex;
  int done = 0;
  run_jobs(2, args.jobs, [&](size_t i) {
    Ran& o = i == 0 ? ref : half;
    o = run_one(u, {"cpu", "double", static_cast<int32_t>(i + 1) * u.ref_substeps, "verlet"});
    const std::lock_guard<std::mutex> lock(progress_mutex);
    progress(++done, 2, "reference dt " + format_number(o.outcome.dt));
  });
  if (!ref.outcome.stable || !half.outcome.stable)
    throw Error(ErrorKind::Numerical,
                "study reference (cpu double, dt " + format_number(half.outcome.dt) +
                    " s) did not complete: " + (half.outcome.stable ? ref.outcome.reason : half.outcome.reason));
  const StudyErrors convergence = compare_trajectories(ref.trajectory, half.trajectory, u.diag);
  const bool converged = convergence.position_max <= args.ref_tolerance;
  if (!converged)
    std::cerr << "organsim: warning: the reference is not converged: halving dt_ref changed positions by "
              << format_number(convergence.position_max) << " of the bbox diagonal (tolerance "
              << format_number(args.ref_tolerance) << "); use a larger --ref-factor\n";

  const Model& model = u.model;
  head = nlohmann::json::object();
  head["scenario"] = args.scenario;
  head["units"] = "SI: dt s, wall time per simulated second s/s; errors relative (positions to the bbox diagonal, "
                  "forces to the reference's peak)";
  head["model"] = {{"points", model.npoint()}, {"springs", model.nspring()}, {"tets", model.ntet()},
                   {"bbox_diagonal", u.diag}};
  head["tick"] = tick;
  head["duration"] = u.scenario.time.duration;
  head["step_policy"] = "the haptic tick is kept: each asked dt becomes tick / round(tick / dt)";
  head["stability"] = to_json(u.prepared.stability);
  head["reference"] = {{"integrator", "verlet"}, {"backend", "cpu"}, {"precision", "double"}, {"dt", ref.outcome.dt},
                       {"dt_half", half.outcome.dt}, {"compared_against", "dt_half"},
                       {"halving_position_change_max", convergence.position_max},
                       {"halving_position_change_rms", convergence.position_rms},
                       {"halving_force_change_rms", convergence.force_rms},
                       {"tolerance", args.ref_tolerance}, {"converged", converged}};
  return std::move(half.trajectory);
}

// Runs configurations `which` (indices into u.configurations), `jobs` at a
// time, each compared with `reference`; done(k, outcome) as each finishes.
void run_configurations(const StudyArgs& args, const StudySetup& u, const std::vector<size_t>& which,
                        const Trajectory& reference, const std::function<void(size_t, StudyOutcome&&)>& done) {
  std::mutex progress_mutex, gl_mutex;
  int finished = 0;
  run_jobs(which.size(), args.jobs, [&](size_t i) {
    const StudyConfiguration& c = u.configurations[which[i]];
    // GL runs one at a time: each holds its own context, and they would
    // share one device.
    std::unique_lock<std::mutex> gl_lock(gl_mutex, std::defer_lock);
    if (c.backend == "gl") gl_lock.lock();
    Ran o = run_one(u, c);
    if (o.outcome.stable) o.outcome.errors = compare_trajectories(o.trajectory, reference, u.diag);
    const std::lock_guard<std::mutex> lock(progress_mutex);
    progress(++finished, static_cast<int>(which.size()),
             c.integrator + " " + c.backend + " " + c.precision + " dt " +
                 format_number(u.scenario.time.tick() / c.substeps));
    done(which[i], std::move(o.outcome));
  });
}

fs::path outdir_of(const StudyArgs& args) {
  return args.outdir.empty() ? fs::path("out") / (fs::path(args.scenario).stem().string() + "_study")
                             : fs::path(args.outdir);
}

// --reference-only: the reference and the plan for the shards. Earlier
// shards' runs are removed first (they may belong to another plan); the plan
// is written last, so a plan on disk means its reference is complete.
void write_reference(const StudyArgs& args, const StudySetup& u) {
  nlohmann::json head;
  const Trajectory reference = run_reference(args, u, head);
  const fs::path outdir = outdir_of(args);
  fs::create_directories(outdir);
  fs::remove(plan_path(outdir));
  fs::remove_all(runs_dir(outdir));
  fs::create_directories(runs_dir(outdir));
  write_file_atomically(reference_path(outdir), [&](std::ostream& out) { out << trajectory_json(reference).dump() << "\n"; });
  StudyPlan plan{u.request, head, u.configurations, u.prepared.stability.dt_crit};
  write_file_atomically(plan_path(outdir), [&](std::ostream& out) { out << plan_json(plan).dump(2) << "\n"; });
  std::cout << "reference: " << reference_path(outdir).string() << "; plan: " << plan_path(outdir).string() << ", "
            << u.configurations.size() << " configurations\n"
            << "next: the same command with --shard i/N (or --shard slurm) instead of --reference-only, then "
               "organsim study --collect " << outdir.string() << "\n";
}

StudyPlan read_plan(const fs::path& outdir) {
  const fs::path path = plan_path(outdir);
  if (!fs::exists(path))
    throw input_error(path.string(), "no such file: run the same study with --reference-only first "
                                     "(docs/stability.md, \"Shards\")");
  return parse_study_plan(read_study_file(path.string()), path.string());
}

// --shard: this slice of the configurations against the written reference,
// each outcome in study_runs/<k>.json as soon as it is known.
// The plan a shard runs: written for the same arguments and scenario text
// (checked before the model is built and settled).
StudyPlan plan_for_shard(const StudyArgs& args) {
  const fs::path outdir = outdir_of(args);
  const StudyPlan plan = read_plan(outdir);
  const nlohmann::json request = request_of(args);
  if (plan.request != request) {
    std::string what = "arguments";
    for (const auto& [key, value] : request.items())
      if (plan.request.value(key, nlohmann::json()) != value) {
        what = key == "scenario_text" ? "scenario file content" : "--" + key + " (it has " +
                                                                      plan.request.value(key, nlohmann::json()).dump() + ")";
        break;
      }
    throw Error(ErrorKind::Usage, plan_path(outdir).string() + ": the reference was written for other " + what +
                                      "; run each shard with the arguments of the --reference-only step");
  }
  return plan;
}

void run_shard(const StudyArgs& args, const Shard& shard, const StudyPlan& plan, const StudySetup& u) {
  const fs::path outdir = outdir_of(args);
  const std::string plan_name = plan_path(outdir).string();
  const nlohmann::json model = {{"points", u.model.npoint()}, {"tets", u.model.ntet()}};
  // parse_study_plan checked that both are whole numbers.
  if (plan.head["model"]["points"] != u.model.npoint() || plan.head["model"]["tets"] != u.model.ntet())
    throw Error(ErrorKind::Usage, plan_name + ": the reference's model differs from this one (" + model.dump() +
                                      "): the mesh changed since --reference-only");
  const Trajectory reference =
      parse_trajectory(read_study_file(reference_path(outdir).string()), reference_path(outdir).string());
  for (const auto& sample : reference.positions)
    if (static_cast<int64_t>(sample.size()) != u.model.npoint())
      throw input_error(reference_path(outdir).string(), "positions: expected " +
                                                             std::to_string(u.model.npoint()) + " points per sample");
  // A configuration with an outcome is done (the reference step emptied
  // study_runs/): a resubmitted shard runs only what is missing.
  std::vector<size_t> which;
  size_t done = 0;
  for (size_t k = 0; k < u.configurations.size(); ++k)
    if (shard.takes(k)) {
      if (fs::exists(run_path(outdir, k)))
        ++done;
      else
        which.push_back(k);
    }
  std::cout << "study shard " << shard.index << "/" << shard.count << ": " << which.size() + done << " of "
            << u.configurations.size() << " configurations, " << done << " done before, " << which.size()
            << " to run\n" << std::flush;
  run_configurations(args, u, which, reference, [&](size_t k, StudyOutcome&& o) {
    write_file_atomically(run_path(outdir, k), [&](std::ostream& out) { out << outcome_record_json(o).dump(2) << "\n"; });
    std::cout << "configuration " << k << " (" << o.integrator << " " << o.backend << " " << o.precision << " dt "
              << format_number(o.dt) << "): " << (o.ran ? (o.stable ? "stable" : "unstable") : "not run") << " -> "
              << run_path(outdir, k).string() << std::endl;
  });
}

// --collect: the table from the plan and every configuration's outcome.
void collect_study(const fs::path& outdir) {
  const StudyPlan plan = read_plan(outdir);
  std::vector<StudyOutcome> runs;
  std::string missing;
  for (size_t k = 0; k < plan.configurations.size(); ++k) {
    const fs::path path = run_path(outdir, k);
    const StudyConfiguration& c = plan.configurations[k];
    if (!fs::exists(path)) {
      missing += (missing.empty() ? "" : ", ") + std::to_string(k) + " (" + c.integrator + " " + c.backend + " " +
                 c.precision + ")";
      continue;
    }
    StudyOutcome o = parse_outcome_record(read_study_file(path.string()), path.string());
    if (o.integrator != c.integrator || o.backend != c.backend || o.precision != c.precision ||
        o.substeps != c.substeps)
      throw input_error(path.string(), "expected configuration " + std::to_string(k) + " of the plan (" +
                                           c.integrator + " " + c.backend + " " + c.precision + ", " +
                                           std::to_string(c.substeps) + " substeps)");
    runs.push_back(std::move(o));
  }
  if (!missing.empty())
    throw Error(ErrorKind::Cases, outdir.string() + ": no outcome yet for configurations " + missing +
                                      " (run or rerun the shards that take them)");
  write_study_outputs(outdir, plan.head, plan.dt_crit, runs);
}

void study_command(const StudyArgs& args) {
  if (!args.collect.empty()) {
    if (!args.scenario.empty() || !args.dts.empty() || args.reference_only || !args.shard.empty())
      throw Error(ErrorKind::Usage, "--collect OUTDIR takes no scenario, --dt, --shard or --reference-only "
                                    "(the folder has the plan)");
    collect_study(args.collect);
    return;
  }
  if (args.scenario.empty() || args.dts.empty())
    throw Error(ErrorKind::Usage, "a scenario and --dt are required (or --collect OUTDIR)");
  if (args.reference_only && !args.shard.empty())
    throw Error(ErrorKind::Usage, "--reference-only and --shard are separate steps; give one");
  if (!args.shard.empty()) {
    // The slice and the plan are checked before the model is built and anything runs.
    const Shard shard = parse_shard(args.shard, [](const char* n) { return std::getenv(n); });
    const StudyPlan plan = plan_for_shard(args);
    return run_shard(args, shard, plan, set_up(args));
  }
  const StudySetup u = set_up(args);
  if (args.reference_only) return write_reference(args, u);

  nlohmann::json head;
  const Trajectory reference = run_reference(args, u, head);
  std::vector<size_t> all(u.configurations.size());
  for (size_t k = 0; k < all.size(); ++k) all[k] = k;
  std::vector<StudyOutcome> runs(all.size());
  run_configurations(args, u, all, reference, [&](size_t k, StudyOutcome&& o) { runs[k] = std::move(o); });
  write_study_outputs(outdir_of(args), head, u.prepared.stability.dt_crit, runs);
}

const bool study_registered = register_command("study", 40, [](CLI::App& root) {
  auto args = std::make_shared<StudyArgs>();
  CLI::App* cmd = root.add_subcommand(
      "study", "Error against run time: run a scenario at several dt [s], backends and precisions, compare each "
               "with a converged double-precision CPU reference, write study.json, study.csv and study.png");
  cmd->add_option("scenario", args->scenario, "Scenario file (see docs/scenarios.md)");
  cmd->add_option("--dt", args->dts, "Integration steps to try, s (comma-separated); the tick is kept")
      ->delimiter(',');
  cmd->add_option("--backend", args->backends, "Backends (comma-separated: cpu, gl)")->delimiter(',');
  cmd->add_option("--precision", args->precisions, "Precisions (comma-separated: double, float)")->delimiter(',');
  cmd->add_option("--integrator", args->integrators,
                  "Integrators (comma-separated: verlet, implicit_euler, implicit_damping; default verlet); an "
                  "implicit one runs on the cpu in double, with the scenario's solver settings")
      ->delimiter(',');
  cmd->add_option("--implicit-dt", args->implicit_dts,
                  "Steps for implicit_euler, s (comma-separated; default: --dt)")
      ->delimiter(',');
  cmd->add_option("--damping-dt", args->damping_dts,
                  "Steps for implicit_damping, s (comma-separated; default: --dt)")
      ->delimiter(',');
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
  cmd->add_flag("--reference-only", args->reference_only,
                "Run only the reference and write it with the plan into OUTDIR, for --shard runs (docs/cluster.md)");
  cmd->add_option("--shard", args->shard,
                  "Run only slice i of N of the configurations (i/N: i, i+N, ...) against the reference "
                  "--reference-only wrote, or \"slurm\": the slice of this Slurm array task");
  cmd->add_option("--collect", args->collect, "Write study.json, study.csv and study.png from OUTDIR's shards");
  cmd->callback([args] { study_command(*args); });
});

}  // namespace
}  // namespace organsim::app
