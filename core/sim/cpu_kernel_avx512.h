#pragma once
// The CPU backend's fast step: AVX-512, one register of points at a time
// (16 in float, 8 in double), one template for both precisions
// (docs/architecture.md, "CPU kernels and how one is chosen"). Same physics
// and state as the generic kernel in cpu_backend.cpp, which stays the
// portable path and, in double, the reference. What differs is the order of
// work: springs are gathered per point and fused with the integration,
// while tets are evaluated once each, one register of tets that share no
// vertex at a time, into fixed force slices added per point in order, so
// that results do not depend on the thread count. Neighbours are read with
// plain loads of their records and transposed in registers
// (avx512_records.h). Not bit-identical to the generic kernel: its sums run
// in another order (tests/core/cpu_kernel_test.cpp).
//
// Compiled only where the compiler targets AVX-512 (the default native
// build); elsewhere avx512_kernel_compiled() is false and the backend uses
// the generic kernel.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/kernel_inputs.h"
#include "core/sim/step_plan.h"

namespace organsim {

// True when this build contains the AVX-512 kernels.
bool avx512_kernel_compiled();

// Why a step plan cannot run on the AVX-512 kernels, float and double (""
// when it can): the one routing point for both.
std::string avx512_kernel_unsupported(const StepPlan& plan, int32_t chunk_size);
// The same for `model`'s plan (its tool does not matter).
std::string avx512_kernel_unsupported(const Model& model);

// The kernel's packed streams and state (defined and only used in the .cpp).
template <class Real>
struct Avx512KernelData;

template <class Real>
class Avx512Kernel {
 public:
  Avx512Kernel();
  ~Avx512Kernel();
  Avx512Kernel(const Avx512Kernel&) = delete;
  Avx512Kernel& operator=(const Avx512Kernel&) = delete;

  // Packs everything the step reads from `model` (rest positions, masses,
  // per-slot spring and tet streams) for `plan`. Called at construction and
  // on every rebuild; the state (u, d) is kept for the points it held, zero
  // for new ones: the caller sets them (set_point).
  void pack(const Model& model, const StepPlan& plan);

  // State of point p: displacement u = x - X and step increment d = u_t - u_{t-1}.
  void get_point(int32_t p, Real u[3], Real d[3]) const;
  void set_point(int32_t p, const Real u[3], const Real d[3]);
  // Axis k of every point's displacement (npoint and more: padding), valid
  // until the next step: for readers of many points (the surface contact,
  // positions()) without a call per point.
  const Real* displacement(int k) const;

  // The rest length of the spring in layout slot e (sutures, per tick).
  void set_spring_rest(int32_t e, Real rest);

  // One substep over all chunks, `threads` OpenMP threads; `partial` gets
  // one reaction per chunk when a tool is active (nchunk entries).
  void step(const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial);

  int32_t nchunk() const;
  size_t bytes() const;  // packed streams and state, for plan()

  using Data = Avx512KernelData<Real>;

 private:
  std::unique_ptr<Data> data_;
};

}  // namespace organsim
