#include "core/sim/thread_choice.h"

#include <algorithm>

namespace organsim {

ThreadChoice::ThreadChoice(int32_t chosen, int32_t other, const Options& options)
    : options_(options), chosen_(chosen), other_(other), interval_(options.first_interval),
      ticks_to_probe_(options.first_interval), early_gap_(options.first_interval) {}

void ThreadChoice::record_tick(int32_t steps, double seconds) {
  if (steps <= 0) return;
  const double per_step = seconds / steps;
  // The median of the last kRecent ticks: it follows load within half of
  // them, and one tick slowed by another process's wake-up (a live
  // session's client, every millisecond), however much, does not move it.
  last_[static_cast<size_t>(nlast_++ % kRecent)] = per_step;
  std::array<double, kRecent> sorted = last_;
  const size_t n = static_cast<size_t>(std::min<int64_t>(nlast_, kRecent));
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.begin() + n);
  recent_step_ = sorted[n / 2];
  --ticks_to_probe_;
  ++ticks_since_probe_;
  if (budget_ > 0 && chosen_ < other_) {
    // A live loop on the fewer count: it stays while its recent steps fit
    // the budget; when they do not, the more is probed (not within
    // early_gap_ ticks of the last probe, as below).
    ticks_to_probe_ = recent_step_ > budget_ && ticks_since_probe_ >= early_gap_ ? 0 : std::max(ticks_to_probe_, 1);
  } else if (best_step_ > 0 && recent_step_ > options_.slowdown * best_step_ && ticks_since_probe_ >= early_gap_) {
    // Load arrived: the recent ticks much slower than the best so far bring
    // the next probe forward, though not within early_gap_ ticks of the last
    // (a probe step in a tick slowed by a passing wake-up only makes it slower).
    ticks_to_probe_ = 0;
  }
  if (best_step_ == 0 || per_step < best_step_) best_step_ = per_step;
}

void ThreadChoice::record_probe(double seconds) {
  ++probes_;
  // A far slower probe is worth repeating early only ever more rarely.
  early_gap_ = recent_step_ > 0 && seconds > options_.much_slower * recent_step_
                   ? std::min(2 * early_gap_, options_.max_interval)
                   : options_.first_interval;
  // Without a tick on chosen() yet there is nothing to compare with. After
  // a switch the old count is probed again at the shortest interval: one
  // probe against a few noisy ticks can be wrong (a live session's client
  // slows the two-thread ticks now and then), and a wrong switch to one
  // thread costs every tick until the next probe.
  // A live loop on the more count moves back to the fewer when that fits
  // the budget with the margin to spare, not only when it is faster.
  const bool back_to_fewer = budget_ > 0 && other_ < chosen_;
  const double bar = back_to_fewer ? budget_ : recent_step_;
  if (recent_step_ > 0 && seconds < (1 - options_.switch_margin) * bar) {
    std::swap(chosen_, other_);
    ++switches_;
    recent_step_ = best_step_ = seconds;
    last_[0] = seconds;
    nlast_ = 1;
    interval_ = ticks_to_probe_ = options_.first_interval;
    ticks_since_probe_ = 0;
    return;
  }
  interval_ = std::min(2 * interval_, options_.max_interval);
  ticks_to_probe_ = interval_;
  ticks_since_probe_ = 0;
}

}  // namespace organsim
