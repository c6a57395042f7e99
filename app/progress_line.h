#pragma once
// A status line on stderr that rewrites itself in place, shown only when
// stderr is a terminal: redirected or piped output gets nothing extra, so
// logs and tests see exactly what they saw before.
#include <chrono>
#include <cstdint>
#include <string>

#include "core/sim/run_observer.h"

namespace organsim::app {

bool stderr_is_terminal();

class ProgressLine {
 public:
  explicit ProgressLine(bool enabled = stderr_is_terminal()) : enabled_(enabled) {}
  ~ProgressLine() { clear(); }
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  bool enabled() const { return enabled_; }
  void show(const std::string& text);  // replaces the line's text
  void clear();                        // erases the line, so later output starts on a clean line

 private:
  bool enabled_;
  bool shown_ = false;
};

// `organsim run`'s line: ticks done, the real-time factor (simulated time
// over wall time) and the wall time left at the rate so far; refreshed at
// most every 0.2 s so it costs nothing measurable.
class RunProgress : public RunObserver {
 public:
  RunProgress(int64_t ticks, double tick_seconds) : ticks_(ticks), tick_seconds_(tick_seconds) {}
  bool enabled() const { return line_.enabled(); }
  void on_start(const Model& model, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;
  void on_finish(const Model& model, Backend& backend) override;

 private:
  using Clock = std::chrono::steady_clock;
  ProgressLine line_;
  int64_t ticks_;
  double tick_seconds_;
  Clock::time_point start_{};
  Clock::time_point last_shown_{};
};

}  // namespace organsim::app
