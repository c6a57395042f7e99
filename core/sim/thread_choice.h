#pragma once
// Keeps the CPU backend's thread count right while a run goes on.
//
// The count is first chosen by timing a few steps at construction, but a
// quiet moment on a loaded machine can make two threads look faster, and a
// two-thread step then waits at every barrier for a thread that is not
// scheduled (a liver run at load 8 did not finish in 300 s). So the run keeps
// timing its ticks on the chosen count and, now and then, one probe step on
// the other count, and switches when the probe is clearly faster than the
// median of the chosen count's last few ticks. Probes
// come at intervals that double after each one (cheap on a steady machine)
// and sooner when the chosen count's recent ticks (their median) become much
// slower than its best (load arrived; a single slow tick is not), though
// ever more rarely while the other count stays far
// slower (on a loaded machine a two-thread probe step can cost 50 one-thread
// steps, and one-thread ticks are noisy). Results do not depend on the
// thread count, so a switch changes only the speed.
//
// A live loop (organsim serve) wants the fewer of the two counts, which
// leaves a core to the network and the client, as long as it keeps up with
// the clock, and the more only when it cannot: set_budget() gives the wall
// seconds a step may take (a share of dt). With a budget, the fewer count
// is kept without probes while its recent steps fit, the more is probed
// when they do not (and taken when faster, as above), and on the more a
// probe of the fewer moves back when it fits with the margin to spare.
//
// Pure bookkeeping on the times it is given, so it can be tested with made-up
// timings; the backend measures them.
#include <array>
#include <cstdint>

namespace organsim {

class ThreadChoice {
 public:
  struct Options {
    int32_t first_interval = 16;   // ticks before the first probe (and the shortest interval)
    int32_t max_interval = 1024;   // ticks; the interval doubles after each probe up to this
    double switch_margin = 0.1;    // switch when the probe is this much faster per step
    double slowdown = 2.0;         // probe early when the recent ticks' median step time exceeds this x the best
    double much_slower = 3.0;      // a probe this many times slower doubles the gap before an early one
  };

  ThreadChoice(int32_t chosen, int32_t other) : ThreadChoice(chosen, other, Options{}) {}
  ThreadChoice(int32_t chosen, int32_t other, const Options& options);

  // True when the next tick should start with one probe step on other().
  bool probe_due() const { return ticks_to_probe_ <= 0; }
  int32_t chosen() const { return chosen_; }
  int32_t other() const { return other_; }
  int32_t switches() const { return switches_; }
  int32_t probes() const { return probes_; }

  // Wall seconds a step may take in a live loop; 0 (the default): none, the
  // faster count is chosen.
  void set_budget(double seconds_per_step) { budget_ = seconds_per_step; }
  double budget() const { return budget_; }

  // A probe step on other() took `seconds`.
  void record_probe(double seconds);
  // A tick's `steps` steps on chosen() took `seconds` in all (a probe step
  // excluded). Ticks with no step are ignored.
  void record_tick(int32_t steps, double seconds);

 private:
  Options options_;
  int32_t chosen_, other_;
  int32_t interval_, ticks_to_probe_, ticks_since_probe_ = 0;
  int32_t early_gap_;  // fewest ticks after a probe before an early one
  // chosen(), time per step: the median of the last kRecent ticks (what a
  // probe is compared with) and the fastest tick since it was chosen; 0: none yet.
  static constexpr int kRecent = 7;
  std::array<double, kRecent> last_{};  // the last ticks' times per step, a ring
  int64_t nlast_ = 0;                   // ticks recorded into last_
  double recent_step_ = 0, best_step_ = 0;
  double budget_ = 0;
  int32_t switches_ = 0, probes_ = 0;
};

}  // namespace organsim
