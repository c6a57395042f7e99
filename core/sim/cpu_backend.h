#pragma once
// The CPU backend: position Verlet with drag fused with the force passes in
// one SIMD kernel written on Google Highway (cpu_kernel_simd.h), float or
// double, on the best instruction set this CPU runs unless `simd` names a
// lower one, with the thread count chosen by timing. Springs are gathered per
// point through the Model's layout (no atomics, deterministic for any thread
// count). It is tested against the reference backend (reference_backend.h:
// the same step in double on the reference forces).
#include <functional>
#include <memory>
#include <string>

#include "core/sim/backend.h"

namespace organsim {

enum class Precision { Double, Float };

struct CpuBackendOptions {
  Precision precision = Precision::Double;
  // 0: chosen by timing a few steps on 1 thread and on all hardware threads
  // at construction, and kept right during a run by timing its ticks and,
  // now and then, one step on the other count (thread_choice.h). Results are
  // bit-identical for any count.
  int32_t threads = 0;
  // The kernel's target by name (simd_targets_compiled()); empty: the
  // default (ORGANSIM_SIMD, else the best this CPU runs). A model the kernel
  // cannot run (simd_kernel_unsupported) is an Error(Backend) naming why.
  std::string simd = "";
  // A live loop's share of the clock (organsim serve; 0: not live). With
  // threads 0 it steps on fewer than all hardware threads, leaving a core
  // to the network and the client (on two, one without timing; on more, the
  // faster of one and all but one, timed at construction), while a step
  // takes at most live_share x dt of wall time, and on all of them only
  // while it takes longer and they are faster (thread_choice.h, the budget).
  double live_share = 0;
};

// What the thread choice is told a run of `steps` steps on `threads`
// threads took, given the `measured` seconds. Empty: the measured time.
// Tests inject timings that make a thread count look slow.
using StepTiming = std::function<double(int32_t threads, int32_t steps, double measured)>;

std::unique_ptr<Backend> make_cpu_backend(const Model& model, const BackendTool& tool,
                                          const CpuBackendOptions& options = {}, StepTiming timing = {});

}  // namespace organsim
