#include "app/sweep_runner.h"

#include <fcntl.h>
#include <sched.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <map>
#include <thread>

#include "app/stop_signals.h"
#include "core/util/error.h"

extern char** environ;

namespace organsim::app {

namespace {

namespace fs = std::filesystem;

pid_t spawn(const ChildJob& job) {
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, STDOUT_FILENO, job.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&files, STDOUT_FILENO, STDERR_FILENO);
  // A child starts with default SIGINT/SIGTERM even where this process was
  // started with them ignored (a background job of a script), so it can be
  // ended.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults, none;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  sigaddset(&defaults, SIGTERM);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  std::vector<char*> argv;
  for (const std::string& a : job.argv) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0], &files, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attr);
  if (rc != 0)
    throw Error(ErrorKind::Output, job.argv[0] + ": cannot start (log " + job.log.string() + "): " + std::strerror(rc));
  return pid;
}

struct Running {
  size_t job;
  std::chrono::steady_clock::time_point start;
};

}  // namespace

ChildRunSummary run_children(const std::vector<ChildJob>& jobs, int parallel,
                             const std::function<void(size_t)>& on_start,
                             const std::function<void(const ChildExit&)>& on_exit) {
  StopSignals signals;
  ChildRunSummary summary;
  std::map<pid_t, Running> running;
  size_t next = 0;
  bool terminated = false;
  try {
    while (true) {
      while (!stop_requested() && next < jobs.size() && static_cast<int>(running.size()) < std::max(1, parallel)) {
        on_start(next);
        running[spawn(jobs[next])] = {next, std::chrono::steady_clock::now()};
        ++next;
      }
      if (stop_requested() && !terminated) {
        summary.interrupted = true;
        for (const auto& [pid, r] : running) kill(pid, SIGTERM);
        terminated = true;
      }
      if (running.empty()) break;
      int status = 0;
      const pid_t pid = waitpid(-1, &status, WNOHANG);
      if (pid <= 0) {
        // Polling (20 ms) instead of a blocking wait, so a signal that arrives
        // just before the wait cannot leave the loop asleep until a child ends.
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        continue;
      }
      const auto it = running.find(pid);
      if (it == running.end()) continue;
      ChildExit e;
      e.job = it->second.job;
      e.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - it->second.start).count();
      e.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 0;
      e.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
      running.erase(it);
      // After an interruption only a clean exit is a result; anything else
      // may be the interruption itself, and the case stays pending.
      if (stop_requested() && (e.exit_code != 0 || e.signal != 0)) {
        ++summary.stopped;
        continue;
      }
      on_exit(e);
    }
  } catch (...) {
    // No child outlives a failed sweep process.
    for (const auto& [pid, r] : running) kill(pid, SIGTERM);
    for (const auto& [pid, r] : running) waitpid(pid, nullptr, 0);
    throw;
  }
  summary.interrupted = summary.interrupted || stop_requested();
  return summary;
}

fs::path own_executable() { return fs::read_symlink("/proc/self/exe"); }

int usable_cpus() {
  if (const char* s = std::getenv("SLURM_CPUS_PER_TASK")) {
    const int n = std::atoi(s);
    if (n > 0) return n;
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace organsim::app
