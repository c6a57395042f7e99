#include "core/sim/thread_choice.h"

#include <algorithm>

namespace organsim {

ThreadChoice::ThreadChoice(int32_t chosen, int32_t other, const Options& options)
    : options_(options), chosen_(chosen), other_(other), interval_(options.first_interval),
      ticks_to_probe_(options.first_interval), early_gap_(options.first_interval) {}

void ThreadChoice::record_tick(int32_t steps, double seconds) {
  if (steps <= 0) return;
  const double per_step = seconds / steps;
  // Weight 1/4 for the newest tick: the average follows a change within a few ticks.
  recent_step_ = recent_step_ == 0 ? per_step : 0.75 * recent_step_ + 0.25 * per_step;
  --ticks_to_probe_;
  ++ticks_since_probe_;
  // Load arrived: the last few ticks' average much slower than the best so
  // far brings the next probe forward, though not within early_gap_ ticks
  // of the last. The average, not the tick: one tick slowed by another
  // process's wake-up (a live session's client, every millisecond) is not
  // load, and a probe step then only makes a slow tick slower.
  if (best_step_ > 0 && recent_step_ > options_.slowdown * best_step_ && ticks_since_probe_ >= early_gap_)
    ticks_to_probe_ = 0;
  if (best_step_ == 0 || per_step < best_step_) best_step_ = per_step;
}

void ThreadChoice::record_probe(double seconds) {
  ++probes_;
  // A far slower probe is worth repeating early only ever more rarely.
  early_gap_ = recent_step_ > 0 && seconds > options_.much_slower * recent_step_
                   ? std::min(2 * early_gap_, options_.max_interval)
                   : options_.first_interval;
  // Without a tick on chosen() yet there is nothing to compare with.
  if (recent_step_ > 0 && seconds < (1 - options_.switch_margin) * recent_step_) {
    std::swap(chosen_, other_);
    ++switches_;
    recent_step_ = best_step_ = seconds;
  }
  interval_ = std::min(2 * interval_, options_.max_interval);
  ticks_to_probe_ = interval_;
  ticks_since_probe_ = 0;
}

}  // namespace organsim
