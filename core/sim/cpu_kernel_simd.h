#pragma once
// The CPU backend's step: one SIMD kernel written once on Google Highway
// (cpu_kernel_simd.cpp, simd_records-inl.h), compiled for several
// instruction sets into one binary (SSE4, AVX2 and AVX-512 on x86-64, NEON
// on arm64, and Highway's portable fallback), the best the CPU has chosen at
// run time unless a lower one is asked for (ORGANSIM_SIMD, --simd).
// One register of points at a time (4 to 16 floats, half as many doubles),
// one template for both precisions (docs/architecture.md, "The CPU
// kernel"): springs are gathered per point and fused with the integration,
// while tets are evaluated once each, one register of tets that share no
// vertex at a time, into fixed force slices added per point in order, so
// that results do not depend on the thread count. Neighbours are read with
// plain loads of their records and transposed in registers.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/kernel_inputs.h"
#include "core/sim/step_plan.h"

namespace organsim {

// An instruction set the kernel is compiled for: Highway's target bit and
// its lower-case name ("avx3" is AVX-512: F, VL, DQ, BW).
struct SimdTarget {
  int64_t bits = 0;
  std::string name;
  bool operator==(const SimdTarget& other) const { return bits == other.bits; }
};

// The targets compiled into this binary, best first, and those of them this
// CPU runs.
std::vector<SimdTarget> simd_targets_compiled();
std::vector<SimdTarget> simd_targets_supported();
// The target a kernel gets when none is asked for: ORGANSIM_SIMD when set
// (a name of simd_targets_compiled(), or "best"), else the best supported.
// An unknown name, or one this CPU cannot run, is an Error(Input) naming
// the variable and the choices.
SimdTarget default_simd_target();
// The target named `name` (as above; `source` names where it came from in
// the error), checked against this CPU.
SimdTarget simd_target_named(const std::string& name, const std::string& source);

// Tests: makes this process behave as on a CPU that runs only the targets
// in `bits` (Highway's target bits; 0: the real CPU again).
void set_simd_targets_for_test(int64_t bits);

// Why `target`'s kernel cannot run a step plan on a layout of
// `chunk_size` ("" when it can): a pass it does not know, or chunks that
// are not whole registers.
std::string simd_kernel_unsupported(const StepPlan& plan, int32_t chunk_size, const SimdTarget& target);

// The same for `model`'s plan (its tool does not matter) on the default target.
std::string simd_kernel_unsupported(const Model& model);

// The kernel of one target and precision: packed streams and state.
template <class Real>
class SimdKernel {
 public:
  virtual ~SimdKernel() = default;

  // Packs everything the step reads from `model` (rest positions, masses,
  // per-slot spring and tet streams) for `plan`. Called at construction and
  // on every rebuild; the state (u, d) is kept for the points it held, zero
  // for new ones: the caller sets them (set_point).
  virtual void pack(const Model& model, const StepPlan& plan) = 0;

  // State of point p: displacement u = x - X and step increment d = u_t - u_{t-1}.
  virtual void get_point(int32_t p, Real u[3], Real d[3]) const = 0;
  virtual void set_point(int32_t p, const Real u[3], const Real d[3]) = 0;
  // Axis k of every point's displacement (npoint and more: padding), valid
  // until the next step: for readers of many points (the surface contact,
  // positions()) without a call per point.
  virtual const Real* displacement(int k) const = 0;

  // The rest length of the spring in layout slot e (sutures, per tick).
  virtual void set_spring_rest(int32_t e, Real rest) = 0;

  // One substep over all chunks, `threads` OpenMP threads; `partial` gets
  // one reaction per chunk when a tool is active (nchunk entries).
  virtual void step(const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) = 0;

  virtual int32_t nchunk() const = 0;
  virtual size_t bytes() const = 0;   // packed streams and state, for plan()
  virtual int32_t lanes() const = 0;  // Real lanes per register
  virtual const SimdTarget& target() const = 0;
};

// The kernel compiled for `target` (one of simd_targets_supported()).
template <class Real>
std::unique_ptr<SimdKernel<Real>> make_simd_kernel(const SimdTarget& target);

}  // namespace organsim
