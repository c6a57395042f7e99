#pragma once
// The CPU backend's fast double step: AVX-512, 8 points per register. The
// same structure as the float kernel (cpu_kernel_avx512.h): neighbours read
// with plain loads of their records and transposed in registers, springs
// gathered per point and fused with the integration, tets evaluated once
// each, 8 per batch, into fixed force slices summed in order (bit-identical
// for any thread count). Not bit-identical to the generic double kernel (the
// reference): its sums run in another order (see tests/core).
//
// Compiled only where the compiler targets AVX-512, like the float kernel;
// which models it runs is decided by avx512_kernel_unsupported().
#include <cstdint>
#include <memory>
#include <vector>

#include "core/model/model.h"
#include "core/sim/kernel_inputs.h"

namespace organsim {

using DoubleStepInputs = KernelStepInputs<double>;

class Avx512DoubleKernel {
 public:
  Avx512DoubleKernel();
  ~Avx512DoubleKernel();
  Avx512DoubleKernel(const Avx512DoubleKernel&) = delete;
  Avx512DoubleKernel& operator=(const Avx512DoubleKernel&) = delete;

  // Packs everything the step reads from `model`; called at construction
  // and on every rebuild. The state is kept for the points it held, zero
  // for new ones: the caller sets them (set_point).
  void pack(const Model& model, const StepPlan& plan);

  // State of point p: displacement u = x - X and step increment d = u_t - u_{t-1}.
  void get_point(int32_t p, double u[3], double d[3]) const;
  void set_point(int32_t p, const double u[3], const double d[3]);

  // One substep over all chunks, `threads` OpenMP threads; `partial` gets
  // one reaction per chunk when a tool is active (nchunk entries).
  void step(const DoubleStepInputs& in, int threads, std::vector<ChunkReaction>& partial);

  int32_t nchunk() const;
  size_t bytes() const;  // packed streams and state, for plan()

  struct Data;  // defined (and only used) in the .cpp

 private:
  std::unique_ptr<Data> data_;
};

}  // namespace organsim
