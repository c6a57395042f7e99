// `organsim sweep SWEEP.json [-o OUTDIR] [--jobs N] [--retry-failed] [--shard i/N|slurm]`
// `organsim sweep SWEEP.json --slurm [--submit] ...`, `organsim sweep --collect OUTDIR`
// Many runs of one scenario: each case of the sweep file runs as its own
// `organsim run` process in OUTDIR/cases/<name>/, so a crash or an unstable
// case is recorded and the others go on. docs/sweep.md, docs/cluster.md.
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "app/command.h"
#include "app/sweep_collect.h"
#include "app/sweep_runner.h"
#include "core/sweep/case_status.h"
#include "core/sweep/shard.h"
#include "core/sweep/slurm_script.h"
#include "core/sweep/sweep_plan.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct SweepArgs {
  std::string sweep;
  std::string outdir;
  int32_t jobs = 0;     // 0: the usable CPUs
  int32_t threads = 0;  // per run; 0: the CPUs shared among the jobs
  bool retry_failed = false;
  std::string shard;
  std::string collect;
  bool list = false;
  bool slurm = false;
  bool submit = false;
  SlurmOptions slurm_options;
  CollectOptions collect_options;
};

fs::path default_outdir(const std::string& sweep) { return fs::path("out") / fs::path(sweep).stem(); }

void print_case_line(size_t n, size_t total, const SweepCase& c, const CaseStatus& s) {
  std::cout << "[" << n << "/" << total << "] " << c.name << ": " << to_string(s.state) << " in " << std::fixed
            << std::setprecision(2) << s.wall_seconds << " s" << std::defaultfloat;
  if (s.state == CaseState::Failed)
    std::cout << " (" << (s.signal ? "signal " + std::to_string(s.signal) : "exit " + std::to_string(s.exit_code))
              << "): " << s.error;
  std::cout << std::endl;
}

// Writes OUTDIR/sweep.sbatch and, with --submit, hands it to sbatch.
void write_slurm(const SweepArgs& args, const Sweep& sweep, const fs::path& outdir) {
  write_plan(outdir, sweep, false);
  const fs::path script_path = outdir / "sweep.sbatch";
  SlurmOptions options = args.slurm_options;
  options.retry_failed = args.retry_failed;
  const std::string script =
      slurm_script(options, sweep.cases.size(), own_executable(), fs::absolute(sweep.file).lexically_normal(), outdir);
  fs::create_directories(outdir / "slurm");
  write_file_atomically(script_path, [&](std::ostream& out) { out << script; });
  std::cout << "slurm:    " << script_path.string() << ": " << sweep.cases.size() << " cases in "
            << slurm_array_tasks(sweep.cases.size(), args.slurm_options) << " array tasks\n";
  if (!args.submit) {
    std::cout << "submit:   sbatch " << script_path.string() << "\n";
    return;
  }
  const std::string cmd = "sbatch --parsable " + shell_quote(script_path.string()) + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) throw Error(ErrorKind::Output, "sbatch: cannot start");
  std::string output;
  char buf[512];
  while (fgets(buf, sizeof buf, pipe)) output += buf;
  const int status = pclose(pipe);
  while (!output.empty() && (output.back() == '\n' || output.back() == '\r')) output.pop_back();
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw Error(ErrorKind::Output, "sbatch " + script_path.string() + " failed: " + output);
  // --parsable prints "jobid" or "jobid;cluster".
  std::cout << "job:      " << output.substr(0, output.find(';')) << "\n";
}

void run_sweep(const SweepArgs& args) {
  if (!args.collect.empty()) {
    if (!args.sweep.empty())
      throw Error(ErrorKind::Usage, "--collect OUTDIR takes no sweep file (the folder has the plan)");
    const ManifestCounts n = collect_sweep(args.collect, args.collect_options);
    if (n.failed || n.pending)
      throw Error(ErrorKind::Cases, args.collect + ": " + std::to_string(n.failed) + " failed and " +
                                        std::to_string(n.pending) + " pending cases (manifest.json names them)");
    return;
  }
  if (args.sweep.empty()) throw Error(ErrorKind::Usage, "a sweep file is required (or --collect OUTDIR)");
  // Everything the command line and the sweep file say is checked before
  // anything is written or run.
  const std::optional<Shard> shard =
      args.shard.empty() ? std::nullopt
                         : std::optional<Shard>(parse_shard(args.shard, [](const char* n) { return std::getenv(n); }));
  const Sweep sweep = load_sweep(args.sweep);
  const fs::path outdir =
      fs::absolute(args.outdir.empty() ? default_outdir(args.sweep) : fs::path(args.outdir)).lexically_normal();

  if (args.list) {
    for (size_t i = 0; i < sweep.cases.size(); ++i) {
      if (shard && !shard->takes(i)) continue;
      std::cout << sweep.cases[i].name << "  " << overrides_json(sweep.cases[i]).dump() << "\n";
    }
    return;
  }
  if (args.slurm) {
    if (shard) throw Error(ErrorKind::Usage, "--slurm makes the shards itself; give no --shard");
    write_slurm(args, sweep, outdir);
    return;
  }

  write_plan(outdir, sweep, shard.has_value());
  std::vector<CaseRecord> records = read_case_records(sweep, outdir);
  std::vector<size_t> selected, to_run;
  int done = 0, failed_skipped = 0;
  for (size_t i = 0; i < sweep.cases.size(); ++i) {
    if (shard && !shard->takes(i)) continue;
    selected.push_back(i);
    const CaseState state = records[i].state;
    if (state == CaseState::Done) {
      ++done;
    } else if (state == CaseState::Failed && !args.retry_failed) {
      ++failed_skipped;
    } else {
      to_run.push_back(i);
    }
  }
  const int cpus = usable_cpus();
  const int jobs = args.jobs > 0 ? args.jobs : cpus;
  const int parallel = std::max<int>(1, std::min<int>(jobs, static_cast<int>(std::max<size_t>(1, to_run.size()))));
  const int threads = args.threads > 0 ? args.threads : std::max(1, cpus / parallel);
  std::cout << "sweep:    " << sweep.cases.size() << " cases of " << sweep.scenario.string();
  if (shard) std::cout << ", shard " << shard->index << "/" << shard->count << ": " << selected.size() << " cases";
  std::cout << "; " << done << " done, " << failed_skipped << " failed (skipped"
            << (failed_skipped ? "; --retry-failed reruns them" : "") << "), " << to_run.size() << " to run, "
            << parallel << " at a time with " << threads << " thread" << (threads == 1 ? "" : "s") << " each\n";
  std::cout << "outputs:  " << outdir.string() << "\n" << std::flush;

  const fs::path exe = own_executable();
  std::vector<ChildJob> children;
  for (size_t i : to_run) {
    const fs::path dir = case_dir(outdir, sweep.cases[i]);
    children.push_back({{exe.string(), "run", (dir / "scenario.json").string(), "-o", dir.string(), "--threads",
                         std::to_string(threads)},
                        dir / "run.log"});
  }
  // A shard shares OUTDIR with other processes: only the unsharded sweep
  // rewrites the manifest (from every case's status.json) as it goes.
  auto update_manifest = [&] {
    if (!shard) write_manifest(sweep, records, outdir);
  };
  update_manifest();
  size_t finished = 0;
  int failed = 0;
  const ChildRunSummary summary = run_children(
      children, parallel,
      [&](size_t k) {
        const SweepCase& c = sweep.cases[to_run[k]];
        const fs::path dir = case_dir(outdir, c);
        fs::create_directories(dir);
        // No status while it runs: interrupted or killed, the case is pending.
        fs::remove(dir / "status.json");
        records[to_run[k]] = CaseRecord{};
        write_file_atomically(dir / "scenario.json", [&](std::ostream& out) { out << c.scenario_text; });
      },
      [&](const ChildExit& e) {
        const SweepCase& c = sweep.cases[to_run[e.job]];
        const fs::path dir = case_dir(outdir, c);
        std::string log;
        try {
          log = read_text_file(dir / "run.log");
        } catch (const Error&) {
        }
        const CaseStatus s = judge_run(c, dir, e.exit_code, e.signal, e.wall_seconds, log);
        write_case_status(dir, s);
        records[to_run[e.job]] = CaseRecord{s.state, s};
        if (s.state == CaseState::Failed) ++failed;
        print_case_line(++finished, to_run.size(), c, s);
        update_manifest();
      });
  if (!shard) collect_sweep(outdir, args.collect_options);
  if (summary.interrupted) {
    throw Error(ErrorKind::Interrupted, "interrupted: " + std::to_string(to_run.size() - finished) +
                                            " cases left pending (their runs were stopped or not started); "
                                            "run the same command again to finish them");
  }
  const int not_done = failed + failed_skipped;
  if (not_done > 0)
    throw Error(ErrorKind::Cases, std::to_string(not_done) + " of " + std::to_string(selected.size()) +
                                      " cases failed (recorded in each case's status.json and run.log" +
                                      (shard ? "" : ", listed in manifest.json") + "); --retry-failed reruns them");
}

const bool sweep_registered = register_command("sweep", 46, [](CLI::App& root) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = root.add_subcommand(
      "sweep",
      "Run a scenario over a grid or list of parameter values (sweep file, JSON): one `organsim run` per case "
      "on all local cores, or as a Slurm job array; resumable; results.csv with each case's figures.");
  cmd->add_option("sweep", args->sweep, "Sweep file (see docs/sweep.md)");
  cmd->add_option("-o,--output", args->outdir, "Output folder (default: out/<sweep file name>)");
  cmd->add_option("--jobs", args->jobs, "Cases run at once (default: the usable CPUs)")->check(CLI::PositiveNumber);
  cmd->add_option("--threads", args->threads, "Threads per run (default: the CPUs shared among the jobs)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--retry-failed", args->retry_failed, "Run failed cases again (done cases are always skipped)");
  cmd->add_option("--shard", args->shard,
                  "Run only slice i of N (i/N: cases i, i+N, ...), or \"slurm\": the slice of this Slurm array task");
  cmd->add_flag("--list", args->list, "Print the cases (name and values) after checking every one; run nothing");
  cmd->add_option("--collect", args->collect,
                  "Write OUTDIR's manifest.json, results.json, results.csv and results.png from the cases' outputs");
  cmd->add_option("--at", args->collect_options.at_times,
                  "Times [s] for force_at_<t> figures (|F| of the nearest sample)")
      ->delimiter(',')
      ->allow_extra_args(false);  // one value per --at: `--at 0.1 s.json` leaves s.json alone
  cmd->add_option("--plot-x", args->collect_options.plot_x,
                  "Swept field on the plot's x axis (default: the first whose values are all numbers)");
  cmd->add_option("--plot-y", args->collect_options.plot_y, "Figure on the plot's y axis (default peak_force)");
  cmd->add_flag("--slurm", args->slurm,
                "Write OUTDIR/sweep.sbatch, a Slurm job array running the sweep (docs/cluster.md)");
  cmd->add_flag("--submit", args->submit, "With --slurm: submit it with sbatch and print the job id");
  cmd->add_option("--cases-per-task", args->slurm_options.cases_per_task,
                  "With --slurm: cases per array task (default 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-parallel", args->slurm_options.max_parallel,
                  "With --slurm: array tasks running at once (--array=...%K; default: no limit)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--cpus-per-task", args->slurm_options.cpus_per_task,
                  "With --slurm: CPUs per array task; the task runs that many cases at once (default 1)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--time", args->slurm_options.time, "With --slurm: time limit per array task (default 01:00:00)");
  cmd->add_option("--partition", args->slurm_options.partition, "With --slurm: partition (default: the cluster's)");
  cmd->add_option("--slurm-setup", args->slurm_options.setup,
                  "With --slurm: a shell line the tasks run first, e.g. 'module load gcc/12'; repeatable")
      ->allow_extra_args(false);
  cmd->callback([args] { run_sweep(*args); });
});

}  // namespace
}  // namespace organsim::app
