#pragma once
// The one place that turns a backend name into a Backend. Every caller (run,
// bench, study) goes through here, so a backend that cannot be created fails
// the same way everywhere: with an error, never a quiet fallback to the CPU.
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/scenario/scenario.h"
#include "core/sim/backend.h"

namespace organsim::app {

struct BackendSelection {
  std::string name = "auto";             // "auto", "cpu" or "gl"
  std::optional<std::string> precision;  // "double" | "float"; default: cpu double, gl float
  int32_t threads = 0;                   // cpu: 0 = all hardware threads
  int32_t gl_threads_per_point = 0;      // gl: invocations per point, 0 = the backend's choice
  bool gl_keep_reaction_positions = false;  // gl: GlBackendOptions::keep_reaction_positions (organsim serve)
  double cpu_live_share = 0;             // cpu: CpuBackendOptions::live_share (organsim serve)
  // cpu: the kernel's target by name ("avx2", ...: CpuBackendOptions::simd;
  // also the implicit integrators' product's); empty: the default.
  std::string cpu_kernel;
  // time.integrator: implicit Euler runs on the CPU in double only
  // (core/sim/reference_backend.h); another backend or precision is refused.
  Integrator integrator = Integrator::Verlet;
  ImplicitOptions implicit;
};

// The backend a scenario runs on, with the command line's --backend,
// --precision and --threads over the scenario's (empty / negative: not given).
// The scenario's precision belongs to the scenario's backend: switching the
// backend on the command line takes the new backend's default precision.
BackendSelection scenario_backend_selection(const Scenario& s, const std::string& backend,
                                            const std::string& precision, int32_t threads);

// The backend names organsim knows (whether or not this build can create them).
const std::vector<std::string>& backend_names();

// "auto" resolved here: the GL backend when the EGL device is a hardware GPU
// (and float is acceptable), the CPU backend otherwise (Mesa's llvmpipe runs
// the shaders on the same cores, several times slower than the CPU backend:
// docs/bench.md); the CPU backend's default precision under auto is float,
// its fast path. Sets selection.name (and the precision when none was asked)
// and returns why, in one line for the run's first lines and its meta. Other
// names are left alone (and return ""): a backend asked for by name never
// falls back.
std::string resolve_auto_backend(BackendSelection& selection);

// Throws Error(Usage) for an unknown name or a precision the backend does not
// offer, Error(Backend) when the backend cannot be created here.
std::unique_ptr<Backend> make_backend(const BackendSelection& selection, const Model& model,
                                      const BackendTool& tool);

}  // namespace organsim::app
