#include "app/backend_factory.h"

#include "core/gl/gl_backend.h"
#include "core/sim/cpu_backend.h"
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
  if (precision == "double") {
    o.precision = Precision::Double;
  } else if (precision == "float") {
    o.precision = Precision::Float;
  } else {
    throw Error(ErrorKind::Usage, "precision: expected \"double\" or \"float\" (got \"" + precision + "\")");
  }
  o.threads = s.threads;
  return make_cpu_backend(model, tool, o);
}

std::unique_ptr<Backend> make_gl(const BackendSelection& s, const Model& model, const BackendTool& tool) {
  if (s.precision && *s.precision != "float") {
    throw Error(ErrorKind::Usage, "the gl backend computes in float (precision \"" + *s.precision + "\" asked)");
  }
  // Throws Error(Backend) naming the EGL call when no context can be made.
  return make_gl_backend(model, tool);
}
}  // namespace

std::unique_ptr<Backend> make_backend(const BackendSelection& selection, const Model& model,
                                      const BackendTool& tool) {
  if (selection.name == "cpu") return make_cpu(selection, model, tool);
  if (selection.name == "gl") return make_gl(selection, model, tool);
  throw Error(ErrorKind::Usage, "unknown backend \"" + selection.name + "\": expected \"cpu\" or \"gl\"");
}

}  // namespace organsim::app
