#include "app/backend_factory.h"

#include <omp.h>

#include "core/gl/egl_context.h"
#include "core/gl/gl_backend.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "core/util/error.h"

namespace organsim::app {

const std::vector<std::string>& backend_names() {
  static const std::vector<std::string> names{"cpu", "gl"};
  return names;
}

namespace {
std::unique_ptr<Backend> make_cpu(const BackendSelection& s, const Model& model, const BackendTool& tool) {
  CpuBackendOptions o;
  const std::string precision = s.precision.value_or("double");
  if (solves_implicitly(s.integrator)) {
    if (precision != "double")
      throw Error(ErrorKind::Usage, std::string("integrator ") + integrator_name(s.integrator) +
                                        " runs on the cpu backend in double precision only (asked: " + precision + ")");
    // Its products gather on the kernel's SIMD target (the scalar gather is the tests' reference).
    ImplicitOptions implicit = s.implicit;
    implicit.simd_product =
        s.cpu_kernel.empty() ? default_simd_target() : simd_target_named(s.cpu_kernel, "cpu backend");
    // Its results do not depend on the thread count: all hardware threads unless asked.
    return make_reference_backend(model, tool, s.integrator, implicit,
                                  s.threads > 0 ? s.threads : omp_get_max_threads());
  }
  if (precision == "double") {
    o.precision = Precision::Double;
  } else if (precision == "float") {
    o.precision = Precision::Float;
  } else {
    throw Error(ErrorKind::Usage, "precision: expected \"double\" or \"float\" (got \"" + precision + "\")");
  }
  o.threads = s.threads;
  o.live_share = s.cpu_live_share;
  o.simd = s.cpu_kernel;
  return make_cpu_backend(model, tool, o);
}

std::unique_ptr<Backend> make_gl(const BackendSelection& s, const Model& model, const BackendTool& tool) {
  if (solves_implicitly(s.integrator))
    throw Error(ErrorKind::Usage, std::string("integrator ") + integrator_name(s.integrator) +
                                      " runs on the cpu backend only (the gl backend integrates by position Verlet)");
  if (s.precision && *s.precision != "float") {
    throw Error(ErrorKind::Usage, "the gl backend computes in float (precision \"" + *s.precision + "\" asked)");
  }
  GlBackendOptions o;
  o.threads_per_point = s.gl_threads_per_point;
  o.keep_reaction_positions = s.gl_keep_reaction_positions;
  // Throws Error(Backend) naming the EGL call when no context can be made.
  return make_gl_backend(model, tool, o);
}
}  // namespace

std::string resolve_auto_backend(BackendSelection& selection) {
  if (selection.name != "auto") return "";
  std::string why;
  if (solves_implicitly(selection.integrator)) {
    selection.name = "cpu";
    if (!selection.precision) selection.precision = "double";
    return "auto chose cpu (" + *selection.precision + "): integrator " + integrator_name(selection.integrator) +
           " runs on the CPU in double";
  }
  if (selection.precision && *selection.precision == "double") {
    selection.name = "cpu";
    why = "double precision asked, which only the CPU backend computes";
  } else {
    try {
      const gl::EglContext probe;
      if (probe.software()) {
        selection.name = "cpu";
        why = "the EGL device is a software renderer (" + probe.renderer() +
              "), slower than the CPU backend on the same cores";
      } else {
        selection.name = "gl";
        why = "the EGL device is a hardware GPU (" + probe.renderer() + ")";
      }
    } catch (const Error& e) {
      selection.name = "cpu";
      why = std::string("no EGL device for the GL backend (") + e.what() + ")";
    }
  }
  if (!selection.precision) selection.precision = "float";
  return "auto chose " + selection.name + " (" + *selection.precision + "): " + why;
}

std::unique_ptr<Backend> make_backend(const BackendSelection& selection, const Model& model,
                                      const BackendTool& tool) {
  if (selection.name == "auto") {
    BackendSelection resolved = selection;
    resolve_auto_backend(resolved);
    return make_backend(resolved, model, tool);
  }
  if (selection.name == "cpu") return make_cpu(selection, model, tool);
  if (selection.name == "gl") return make_gl(selection, model, tool);
  throw Error(ErrorKind::Usage, "unknown backend \"" + selection.name + "\": expected \"auto\", \"cpu\" or \"gl\"");
}

BackendSelection scenario_backend_selection(const Scenario& s, const std::string& backend,
                                            const std::string& precision, int32_t threads) {
  BackendSelection selection;
  selection.name = backend.empty() ? s.backend.name : backend;
  const bool backend_switched = !backend.empty() && backend != s.backend.name;
  if (!precision.empty())
    selection.precision = precision;
  else if (!backend_switched)
    selection.precision = s.backend.precision;
  selection.threads = threads >= 0 ? threads : s.backend.threads;
  selection.integrator = s.time.integrator;
  selection.implicit = s.time.implicit;
  return selection;
}

}  // namespace organsim::app
