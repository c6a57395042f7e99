#pragma once
// The CPU backend's fast float step: AVX-512, 16 points per register
// (docs/architecture.md, "CPU kernels and how one is chosen"). Same physics,
// layout and state as the generic kernel in cpu_backend.cpp (which stays the
// portable fallback and the double-precision reference); what differs is how
// neighbours are read: each point's state is one 32-byte record (x, y, z, 0,
// dx, dy, dz, 0) and a group of 16 neighbours is fetched with plain loads and
// transposed in registers, because a 16-lane hardware gather costs several
// times more here.
//
// Compiled only where the compiler targets AVX-512 (the default native build
// on this machine); elsewhere avx512_kernel_compiled() is false and the
// backend uses the generic kernel.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/sim/kernel_inputs.h"
#include "core/sim/step_plan.h"
#include "core/sim/tool.h"

namespace organsim {

// True when this build contains the AVX-512 kernel.
bool avx512_kernel_compiled();

// Why a step plan cannot run on the AVX-512 kernels, float and double (""
// when it can): the one routing point for both. They need the layout's
// chunks to be whole groups of 16 points.
std::string avx512_kernel_unsupported(const StepPlan& plan, int32_t chunk_size);
// The same for `model`'s plan (its tool does not matter).
std::string avx512_kernel_unsupported(const Model& model);

using FloatStepInputs = KernelStepInputs<float>;

class Avx512FloatKernel {
 public:
  Avx512FloatKernel();
  ~Avx512FloatKernel();
  Avx512FloatKernel(const Avx512FloatKernel&) = delete;
  Avx512FloatKernel& operator=(const Avx512FloatKernel&) = delete;

  // Packs everything the step reads from `model` (rest positions, masses,
  // per-slot spring and tet streams). Called at construction and on every
  // rebuild; the state (u, d) is sized to the model with zeros for points
  // it did not hold before: the caller sets them (set_point).
  void pack(const Model& model, const StepPlan& plan);

  // State of point p: displacement u = x - X and step increment d = u_t - u_{t-1}.
  void get_point(int32_t p, float u[3], float d[3]) const;
  void set_point(int32_t p, const float u[3], const float d[3]);

  // One substep over all chunks, `threads` OpenMP threads; `partial` gets
  // one reaction per chunk when a tool is active (nchunk entries).
  void step(const FloatStepInputs& in, int threads, std::vector<ChunkReaction>& partial);

  int32_t nchunk() const;
  size_t bytes() const;  // packed streams and state, for plan()

  struct Data;  // defined (and only used) in the .cpp

 private:
  std::unique_ptr<Data> data_;
};

}  // namespace organsim
