#include "core/run/change_worker.h"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <chrono>

namespace organsim {

void ChangeWorker::start(TopologyEvents& events, const Model& current, std::vector<Vec3> x, double t0, double t1,
                         double dt, const ToolSpec* tool, const Backend& backend, const OffPathPlan& when) {
  at_ = when.at;
  future_ = std::async(std::launch::async, [&events, &current, x = std::move(x), t0, t1, dt, tool, &backend] {
    // The worker's thread yields to the run loop's stepping threads (and to
    // a live client on the same cores): a change may go in later, but it
    // takes no tick's time. It leaves a real-time policy it inherited from
    // the loop (organsim serve --realtime-priority) first; Linux gives each
    // thread its own nice value.
    const sched_param normal{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 19);
    Built b;
    auto next = std::make_unique<Model>();
    if (!events.before_tick(t0, t1, current, x, *next)) return b;
    const auto check_start = std::chrono::steady_clock::now();
    const CriticalStepOptions step_options = critical_step_options(*next, tool);
    b.guaranteed = events.guaranteed_step(current, *next, step_options);
    if (!(dt <= b.guaranteed)) b.full = estimate_critical_step(*next, step_options);
    b.check_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - check_start).count();
    const auto start = std::chrono::steady_clock::now();
    b.prepared = backend.prepare(*next);
    b.prepare_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    b.next = std::move(next);
    return b;
  });
}

bool ChangeWorker::due(double t0, double dt) const {
  if (!busy()) return false;
  // As the run's tick events: the first tick that starts at or after the time, half a step of slack.
  if (at_) return t0 >= *at_ - 0.5 * dt;
  return future_.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

ChangeWorker::Built ChangeWorker::take() { return future_.get(); }

void ChangeWorker::abandon() {
  if (!busy()) return;
  try {
    future_.get();
  } catch (...) {
    // The run is ending with its own result or error.
  }
}

}  // namespace organsim
