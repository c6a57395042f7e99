#pragma once
// Runs child processes (the sweep's `organsim run` of each case), at most N
// at once, each with its output in a log file. SIGINT or SIGTERM stops the
// launching, ends the running children (SIGTERM) and waits for them, so an
// interrupted sweep leaves no process behind and no case half-recorded.
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace organsim::app {

struct ChildJob {
  std::vector<std::string> argv;  // argv[0] is the executable's path
  std::filesystem::path log;      // stdout and stderr, truncated at the start
};

struct ChildExit {
  size_t job = 0;           // index into the jobs
  int exit_code = 0;        // 0 when killed by a signal
  int signal = 0;           // the signal that ended it, 0 when it exited
  double wall_seconds = 0;  // s, from spawn to exit
};

struct ChildRunSummary {
  bool interrupted = false;  // SIGINT/SIGTERM arrived; later jobs were not started
  size_t stopped = 0;        // children ended because of the interruption (not reported)
};

// Starts jobs in order, at most `parallel` at once; `on_start(job)` before a
// job is spawned, `on_exit` after each child ends by itself (also during an
// interruption, if it exited 0). Throws Error(Output) when a child cannot be
// spawned (its log cannot be opened, the executable is missing).
ChildRunSummary run_children(const std::vector<ChildJob>& jobs, int parallel,
                             const std::function<void(size_t)>& on_start,
                             const std::function<void(const ChildExit&)>& on_exit);

// This process's executable (/proc/self/exe), to run cases with the same build.
std::filesystem::path own_executable();

// CPUs this process may use: SLURM_CPUS_PER_TASK inside a Slurm job, else
// the affinity mask's count (what taskset or a cgroup allows).
int usable_cpus();

}  // namespace organsim::app
