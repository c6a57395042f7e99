#pragma once
// The sbatch script that runs a sweep as a Slurm job array: one array task
// per shard, each task `organsim sweep SWEEP --shard slurm` on the shared
// output folder. docs/cluster.md.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace organsim {

struct SlurmOptions {
  int cases_per_task = 1;         // cases run by one array task (packs large sweeps into small arrays)
  int max_parallel = 0;           // array tasks running at once (%K); 0: no limit
  int cpus_per_task = 1;          // each task runs this many cases at once, one thread each
  std::string time = "01:00:00";  // per task, as sbatch --time
  std::string partition;          // empty: the cluster's default
  std::string job_name = "organsim-sweep";
  std::vector<std::string> setup;  // shell lines before the run (module load ..., source ...)
  bool retry_failed = false;       // the tasks rerun failed cases too
};

// Array tasks for `ncases` cases.
int slurm_array_tasks(size_t ncases, const SlurmOptions& o);

// The script's text. `organsim` is the executable the tasks run (absolute),
// `sweep_file` and `outdir` absolute; the tasks' Slurm logs go to
// OUTDIR/slurm/<job>_<task>.out.
std::string slurm_script(const SlurmOptions& o, size_t ncases, const std::filesystem::path& organsim,
                         const std::filesystem::path& sweep_file, const std::filesystem::path& outdir);

// Single-quoted for a POSIX shell.
std::string shell_quote(const std::string& s);

}  // namespace organsim
