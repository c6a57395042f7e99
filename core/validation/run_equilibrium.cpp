#include "core/validation/run_equilibrium.h"

#include <cmath>
#include <string>

#include "core/sim/reference_backend.h"
#include "core/util/error.h"

namespace organsim {

namespace {
// A step long enough that M / h^2 is below 1e-6 of the stiffness of any
// tissue organsim meshes (E >= 100 Pa at cells <= 10 cm): each step is a
// Newton solve of the static equilibrium.
constexpr double kStep = 1.0;  // s
constexpr int32_t kLoweringSteps = 8;
constexpr int32_t kMaxSteps = 80;
constexpr double kSettled = 1e-4;  // relative change of the force, far below the percent-level errors validated
}  // namespace

HeldToolEquilibrium held_tool_equilibrium(const Model& model, const BackendTool& tool, const Vec3& from,
                                          const Vec3& to) {
  ImplicitOptions options;
  // Newton's line search keeps the first steps from overshooting into a
  // contact that alternates between two states (one linearisation per step
  // does that at this step length); the rest factor makes each solve a few
  // CG iterations.
  options.newton_iterations = 4;
  options.cg_tolerance = 1e-8;
  options.cg_max_iterations = 500;
  options.preconditioner = Preconditioner::RestCholesky;
  const auto backend = make_reference_backend(model, tool, Integrator::ImplicitEuler, options);
  TickRequest request;
  request.dt = kStep;
  request.substeps = 1;
  request.tool_active = true;
  HeldToolEquilibrium result;
  double last[3] = {0, 0, 0};  // the force's magnitude 1, 2 and 3 steps back
  for (result.steps = 1; result.steps <= kMaxSteps; ++result.steps) {
    const double lowered = std::min(1.0, static_cast<double>(result.steps - 1) / kLoweringSteps);
    const double next = std::min(1.0, static_cast<double>(result.steps) / kLoweringSteps);
    request.tool_from = from + lowered * (to - from);
    request.tool_to = from + next * (to - from);
    // The reaction is the contact's at the step's start: at the held pose
    // from the step after the lowering ends. A tool that never touches
    // settles at 0.
    result.reaction = backend->tick(request);
    const double force = result.reaction.force.norm();
    const auto close = [&](double other) { return std::abs(force - other) <= kSettled * force; };
    if (result.steps > kLoweringSteps + 3 && close(last[0]) && close(last[1]) && close(last[2])) return result;
    last[2] = last[1], last[1] = last[0], last[0] = force;
  }
  throw Error(ErrorKind::Numerical, "the held tool's equilibrium did not settle in " + std::to_string(kMaxSteps) +
                                        " Newton-solved steps at contact stiffness " +
                                        std::to_string(tool.contact_stiffness) + " N/m (force " +
                                        std::to_string(last[0]) + " N, then " + std::to_string(last[1]) + " N)");
}

}  // namespace organsim
