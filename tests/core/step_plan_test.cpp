// The step plan (core/sim/step_plan.h): which passes a scene's step has, in
// order, and that every CPU kernel names exactly these in its plan().
#include <gtest/gtest.h>

#include "core/mesh/tet_mesh.h"
#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/reference_backend.h"
#include "core/sim/step_plan.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace step_plan_test {
namespace {

struct Scene {
  const char* what;
  Material material;
  Vec3 gravity;
  BackendTool tool;
  std::vector<Pass> expected;
};

Model scene_model(const Scene& scene) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), 4, 4, 2);
  return build_model(mesh, scene.material, testing::fixed_bottom_options(scene.gravity), "test box");
}

std::vector<Scene> scenes() {
  auto material = [](std::optional<double> nu, double volume_modulus, ShearFormulation shear) {
    Material m;
    m.young_modulus = 3000;
    m.poisson_ratio = nu;
    m.volume_modulus = volume_modulus;
    m.shear_formulation = shear;
    return m;
  };
  const BackendTool none{}, push{true, ToolMode::Push, 0.02, 200}, pull{true, ToolMode::Pull, 0.02, 200},
      push_points{true, ToolMode::Push, 0.02, 200, ToolContact::Points};
  const Vec3 g(0, 0, -9.81), no_g = Vec3::Zero();
  using P = Pass;
  return {
      {"springs only", material(std::nullopt, 0, ShearFormulation::Smoothed), no_g, none, {P::Springs, P::Integrate}},
      {"per-tet volume, gravity, push (surface contact)", material(std::nullopt, 20000, ShearFormulation::Smoothed), g,
       push, {P::SurfaceContact, P::Springs, P::Volume, P::Gravity, P::ToolContact, P::Integrate}},
      {"per-tet volume, push on the points", material(std::nullopt, 20000, ShearFormulation::Smoothed), no_g,
       push_points, {P::Springs, P::Volume, P::ToolContact, P::Integrate}},
      {"nu 0.45 (nodal volume), pull", material(0.45, 0, ShearFormulation::Smoothed), no_g, pull,
       {P::NodalPressure, P::Springs, P::Volume, P::ToolContact, P::Integrate}},
      {"nu 0.1 smoothed shear, gravity", material(0.1, 0, ShearFormulation::Smoothed), g, none,
       {P::ShearSmoothing, P::Springs, P::ShearElement, P::Gravity, P::Integrate}},
      {"nu 0.1 per-tet shear, push", material(0.1, 0, ShearFormulation::PerTet), no_g, push,
       {P::SurfaceContact, P::Springs, P::ShearElement, P::ToolContact, P::Integrate}},
  };
}

std::vector<std::string> names(const std::vector<Pass>& passes) {
  std::vector<std::string> out;
  for (Pass p : passes) out.push_back(pass_name(p));
  return out;
}

std::vector<std::string> names(const Plan& plan) {
  std::vector<std::string> out;
  for (const PassInfo& p : plan.passes) out.push_back(p.name);
  return out;
}

TEST(StepPlan, PassesFollowTheModelAndTheTool) {
  for (const Scene& scene : scenes()) {
    const Model model = scene_model(scene);
    const StepPlan plan = make_step_plan(model, scene.tool);
    EXPECT_EQ(names(plan.passes), names(scene.expected)) << scene.what;
    EXPECT_EQ(plan.sutures, 0) << scene.what;
  }
}

// The kernel (in both precisions) and the reference backend run from the
// plan and name its passes as the plan does, in its order.
TEST(StepPlan, TheKernelAndTheReferenceNameThePlansPasses) {
  for (const Scene& scene : scenes()) {
    const Model model = scene_model(scene);
    std::vector<std::unique_ptr<Backend>> backends;
    backends.push_back(make_reference_backend(model, scene.tool, Integrator::Verlet));
    for (const Precision precision : {Precision::Double, Precision::Float})
      backends.push_back(make_cpu_backend(model, scene.tool, {precision, 1}));
    for (const auto& backend : backends) {
      EXPECT_EQ(names(backend->step_plan().passes), names(scene.expected)) << scene.what;
      EXPECT_EQ(names(backend->plan()), names(scene.expected)) << scene.what << ", " << backend->device();
    }
  }
}

// A rebuild recomputes the plan: sutures appear in it, and the backend
// keeps the simd kernel with the same passes.
TEST(StepPlan, RebuildWithSuturesRecomputesThePlan) {
  const Scene scene = scenes()[2];
  const Model model = scene_model(scene);
  auto backend = make_cpu_backend(model, scene.tool, {Precision::Float, 1});
  Suture suture;
  suture.ends = {0, model.npoint() - 1};
  suture.k = 10;
  suture.length = (model.rest_position[suture.ends[1]] - model.rest_position[0]).norm();
  const Model sutured = add_sutures(model, {suture});
  backend->rebuild(sutured);
  EXPECT_EQ(backend->step_plan().sutures, 1);
  EXPECT_EQ(names(backend->plan()), names(scene.expected));
  // Sutures run on the simd kernel: the rebuilt plan keeps it.
  EXPECT_EQ(simd_kernel_unsupported(backend->step_plan(), sutured.layout.chunk_size, default_simd_target()), "");
  const std::string kernel = "simd (" + default_simd_target().name + ") kernel";
  EXPECT_NE(backend->device().find(kernel), std::string::npos) << backend->device();
  ASSERT_EQ(backend->plan().per_tick.size(), 1u);
  EXPECT_EQ(backend->plan().per_tick[0].name, "suture-rest");
}

}  // namespace
}  // namespace step_plan_test
}  // namespace organsim
