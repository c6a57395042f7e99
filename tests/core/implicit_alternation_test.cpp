// A state that swings between two (core/sim/reference_backend.h,
// IntegratorStats::alternating_steps): a sphere held 2 mm into a slab with
// a contact ten times stiffer than the scenario default, stepped at 20 ms
// with one linearisation per step, overshoots the contact every step and
// settles into a two-state cycle whose CG converges every time; the count
// says so and the run's warning names it. Newton iterations (their line
// search) or a 1 ms step settle instead, and count nothing.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/run/integrator_report.h"
#include "core/sim/reference_backend.h"

namespace organsim {
namespace implicit_alternation_test {
namespace {

struct HeldSphere {
  int64_t steps = 0, alternating = 0;
  std::string warning;
  nlohmann::json meta;
};

HeldSphere hold_sphere(double dt, int32_t newton_iterations) {
  // 10 x 8 x 6 cm, 11 x 8 x 6 cells, the base held; springs alone, 10 kPa.
  Material material;
  material.young_modulus = 1e4;
  ModelOptions options;
  FixedSelector base;
  base.kind = FixedSelector::Kind::Box;
  base.min = Vec3::Constant(-1);
  base.max = Vec3(1, 1, 1e-4);
  options.fixed = {base};
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3(0.10, 0.08, 0.06), 11, 8, 6), material, options);
  BackendTool tool;
  tool.present = true;
  tool.radius = 0.02;
  tool.contact_stiffness = 2000;
  tool.contact = ToolContact::Surface;
  tool.hertz_layer = true;
  ImplicitOptions implicit;
  implicit.newton_iterations = newton_iterations;
  implicit.preconditioner = Preconditioner::RestCholesky;
  implicit.cg_tolerance = 1e-8;
  implicit.cg_max_iterations = 500;
  auto backend = make_reference_backend(model, tool, Integrator::ImplicitEuler, implicit, 2);
  // Lowered from clear of the top over 8 steps to 2 mm deep, then held.
  const Vec3 from(0.05, 0.04, 0.06 + 1.05 * 0.02), held(0.05, 0.04, 0.06 + 0.02 - 0.002);
  TickRequest request;
  request.dt = dt;
  request.substeps = 1;
  request.tool_active = true;
  for (int step = 1; step <= 40; ++step) {
    request.tool_from = from + std::min(1.0, (step - 1) / 8.0) * (held - from);
    request.tool_to = from + std::min(1.0, step / 8.0) * (held - from);
    backend->tick(request);
  }
  HeldSphere out;
  out.steps = backend->integrator_stats()->steps();
  out.alternating = backend->integrator_stats()->alternating_steps;
  out.warning = integrator_warning(*backend);
  out.meta = integrator_meta(*backend);
  EXPECT_EQ(backend->integrator_stats()->unconverged_steps, 0);  // CG converged every time: it cannot tell
  return out;
}

TEST(ImplicitEuler, AStateSwingingBetweenTwoIsCountedAndWarned) {
  const HeldSphere cycle = hold_sphere(0.02, 1);
  EXPECT_EQ(cycle.steps, 40);
  // Every held step after the cycle sets in (measured: from about step 12).
  EXPECT_GT(cycle.alternating, 20);
  EXPECT_EQ(cycle.meta["alternating_steps"], cycle.alternating);
  EXPECT_DOUBLE_EQ(cycle.meta["alternating_share"].get<double>(), cycle.alternating / 40.0);
  EXPECT_NE(cycle.warning.find("swung back and forth between two in " + std::to_string(cycle.alternating) + " of 40"),
            std::string::npos)
      << cycle.warning;
  EXPECT_NE(cycle.warning.find("newton_iterations"), std::string::npos) << cycle.warning;
}

TEST(ImplicitEuler, ASettlingStateCountsNoAlternation) {
  for (const auto& [dt, newton] : {std::pair{0.02, 8}, std::pair{0.001, 1}}) {
    const HeldSphere settled = hold_sphere(dt, newton);
    EXPECT_EQ(settled.alternating, 0) << "dt " << dt << ", newton_iterations " << newton;
    EXPECT_EQ(settled.warning, "") << "dt " << dt << ", newton_iterations " << newton;
  }
}

}  // namespace
}  // namespace implicit_alternation_test
}  // namespace organsim
