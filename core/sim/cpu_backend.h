#pragma once
// The CPU backend. Its generic kernel in double precision is the reference
// every other path is tested against. Springs are gathered per point through
// the Model's layout (no atomics, deterministic for any thread count) and
// force evaluation is fused with Verlet integration.
//
// Kernels, chosen at construction (and again at every rebuild):
// - simd: one source on Google Highway for every instruction set
//   (cpu_kernel_simd.h), the best this CPU has unless `simd` names a lower
//   one; several times faster than generic;
// - generic: portable C++ the compiler vectorises, any precision, any layout;
//   the double-precision reference.
// `Auto` takes simd where it can and says so in device() and plan().
#include <functional>
#include <memory>
#include <string>

#include "core/sim/backend.h"

namespace organsim {

enum class Precision { Double, Float };

enum class CpuKernel { Auto, Generic, Simd };

struct CpuBackendOptions {
  Precision precision = Precision::Double;
  // 0: chosen by timing a few steps on 1 thread and on all hardware threads
  // at construction, and kept right during a run by timing its ticks and,
  // now and then, one step on the other count (thread_choice.h). Results are
  // bit-identical for any count.
  int32_t threads = 0;
  // Simd when it cannot run here (an unsupported
  // model) is an Error(Backend) naming why; Auto never fails.
  CpuKernel kernel = CpuKernel::Auto;
  // The simd kernel's target by name (simd_targets_compiled()); empty: the
  // default (ORGANSIM_SIMD, else the best this CPU runs).
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
