#pragma once
// SIGINT and SIGTERM as a request to stop cleanly (`organsim sweep` leaves
// unfinished cases pending, `organsim serve` ends its session and writes its
// record): while a StopSignals lives, the signals set stop_requested()
// instead of killing the process; the previous handlers come back after.
#include <atomic>
#include <csignal>

namespace organsim::app {

// Set by the handler; lock-free, so reading it is safe anywhere.
const std::atomic<bool>& stop_requested();

class StopSignals {
 public:
  StopSignals();
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction old_int_ {
  }, old_term_{};
};

}  // namespace organsim::app
