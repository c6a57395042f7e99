#include "core/render/force_plot_recorder.h"

namespace organsim {

ForcePlotRecorder::ForcePlotRecorder(const std::filesystem::path& path, double tick, int64_t expected_ticks)
    : path_(path), tick_(tick) {
  t_.reserve(static_cast<size_t>(expected_ticks));
  force_.reserve(static_cast<size_t>(expected_ticks));
}

void ForcePlotRecorder::on_start(const Model& /*model*/, Backend& backend) {
  latency_ = backend.reaction_latency_ticks();
}

void ForcePlotRecorder::on_tick(const Model& /*model*/, Backend& /*backend*/, const TickInfo& info) {
  // A backend with a readback latency of L ticks returns at tick i the
  // reaction of tick i - L: plot it at the time it belongs to, and drop the
  // L leading zeros that stand for "not known yet".
  if (info.tick < latency_) return;
  t_.push_back(info.t - latency_ * tick_);
  force_.push_back(info.reaction.force);
}

void ForcePlotRecorder::on_finish(const Model& /*model*/, Backend& /*backend*/) {
  write_force_plot(path_, t_, force_);
}

}  // namespace organsim
