#include "app/progress_line.h"

#include <unistd.h>

#include <cstdio>
#include <iostream>

#include "core/run/integrator_report.h"
#include "core/util/format.h"

namespace organsim::app {

bool stderr_is_terminal() { return isatty(STDERR_FILENO) == 1; }

void ProgressLine::show(const std::string& text) {
  if (!enabled_) return;
  // Carriage return, the text, then erase to the end of the line (ANSI EL).
  std::cerr << "\r" << text << "\x1b[K" << std::flush;
  shown_ = true;
}

void ProgressLine::clear() {
  if (!shown_) return;
  std::cerr << "\r\x1b[K" << std::flush;
  shown_ = false;
}

void RunProgress::on_start(const Model&, Backend&) { start_ = Clock::now(); }

void RunProgress::on_tick(const Model&, Backend& backend, const TickInfo& info) {
  if (!line_.enabled()) return;
  const Clock::time_point now = Clock::now();
  const int64_t done = info.tick + 1;
  if (done < ticks_ && now - last_shown_ < std::chrono::milliseconds(200)) return;
  last_shown_ = now;
  const double wall = std::chrono::duration<double>(now - start_).count();
  const double simulated = static_cast<double>(done) * tick_seconds_;
  const double left = wall / static_cast<double>(done) * static_cast<double>(ticks_ - done);
  line_.show("organsim run: tick " + std::to_string(done) + "/" + std::to_string(ticks_) + " (" +
             format_number(100.0 * static_cast<double>(done) / static_cast<double>(ticks_), "%.0f") +
             " %), real-time factor " + format_number(wall > 0 ? simulated / wall : 0, "%.3g") + ", " +
             format_number(left, "%.0f") + " s left" +
             [&] {
               const std::string cg = integrator_progress(backend);
               return cg.empty() ? cg : ", " + cg;
             }());
}

void RunProgress::on_finish(const Model&, Backend&) { line_.clear(); }

}  // namespace organsim::app
