#pragma once
// The CPU backend. In double precision it is the reference every other path
// is tested against; in float it is the fast path. Both gather springs and
// tets per point through the Model's layout (no atomics, deterministic for
// any thread count) and fuse force evaluation with Verlet integration.
#include <memory>

#include "core/sim/backend.h"

namespace organsim {

enum class Precision { Double, Float };

struct CpuBackendOptions {
  Precision precision = Precision::Double;
  int32_t threads = 0;  // 0: all hardware threads
};

std::unique_ptr<Backend> make_cpu_backend(const Model& model, const BackendTool& tool,
                                          const CpuBackendOptions& options = {});

}  // namespace organsim
