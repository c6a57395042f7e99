// Tool contact / grasp stiffness per point (Model::tool_k_scale): a light
// point must not set the time step, and the kernels must apply the scale.
#include <gtest/gtest.h>

#include "core/sim/cpu_backend.h"
#include "core/stability/critical_step.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace tool_stiffness_test {
namespace {

// A 4x4x4-cell box whose outer cell layers are 0.5 mm thick against 10 mm
// inside: its corner points carry ~1e-4 of the median point mass.
Model box_with_tiny_corners() {
  const double coords[] = {0, 0.0005, 0.0105, 0.0205, 0.0305, 0.031};
  TetMesh mesh = make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(5), 5, 5, 5);  // unit cells, then remapped
  for (Vec3& p : mesh.points)
    for (int a = 0; a < 3; ++a) p[a] = coords[static_cast<int>(std::lround(p[a]))];
  Material m;
  m.density = 1000;
  m.young_modulus = 5000;
  m.spring_damping_time = 0;
  m.viscous_damping = 0;
  ModelOptions options;
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-6);
  base.normal = Vec3(0, 0, -1);
  options.fixed = {base};
  return build_model(mesh, m, options);
}

TEST(ToolStiffness, LightPointsGetAProportionallySofterTool) {
  const Model model = box_with_tiny_corners();
  double lightest = 1e300, heaviest = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.fixed[i]) continue;
    lightest = std::min(lightest, model.mass[i]);
    heaviest = std::max(heaviest, model.mass[i]);
    EXPECT_LE(model.tool_k_scale[i], 1.0);
  }
  ASSERT_LT(lightest, 1e-3 * heaviest);  // the mesh really has tiny corner masses
  // The scale is m / median: a heavy point keeps the full stiffness.
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.mass[i] == heaviest) {
      EXPECT_EQ(model.tool_k_scale[i], 1.0);
    }
  }
}

TEST(ToolStiffness, GraspOnTinyCornersLeavesTheStepToTheMaterial) {
  const Model model = box_with_tiny_corners();
  const StabilityReport material = estimate_critical_step(model, {});
  // A grasp on every free point, stiff enough to add 20 % to the omega^2 of
  // a median-mass point: with the per-mass scale the step may shrink by at
  // most 1/sqrt(1.2) (0.91; 0.85 allows the power iteration's 1e-5 and the
  // mode mixing); with one k for all points the corners would dominate.
  std::vector<double> free_mass;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) free_mass.push_back(model.mass[i]);
  std::nth_element(free_mass.begin(), free_mass.begin() + free_mass.size() / 2, free_mass.end());
  CriticalStepOptions tool;
  tool.tool_contact_stiffness = 0.2 * material.lambda_max * free_mass[free_mass.size() / 2];
  const StabilityReport scaled = estimate_critical_step(model, tool);
  EXPECT_GT(scaled.dt_crit, 0.85 * material.dt_crit);

  Model unscaled = model;
  unscaled.tool_k_scale.clear();  // the old rule: k_c on every point alike
  const StabilityReport old = estimate_critical_step(unscaled, tool);
  EXPECT_LT(old.dt_crit, 0.3 * material.dt_crit);
}

TEST(ToolStiffness, CpuPushContactOnALightPointUsesItsScale) {
  const Model model = box_with_tiny_corners();
  // The top corner (0.031, 0.031, 0.031): a sphere centred outside it along
  // the diagonal, overlapping it by 0.1 mm and no other point.
  int32_t corner = -1;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if ((model.rest_position[i] - Vec3::Constant(0.031)).norm() < 1e-12) corner = i;
  ASSERT_GE(corner, 0);
  const double radius = 0.002, depth = 1e-4;
  const Vec3 centre = Vec3::Constant(0.031) + (radius - depth) * Vec3::Constant(1).normalized();
  BackendTool tool;
  tool.present = true;
  tool.mode = ToolMode::Push;
  tool.radius = radius;
  tool.contact_stiffness = 1000;
  // The point penalty's own scale (surface contact spreads the corner's
  // triangles over their corners: SurfaceContact.StiffnessPerPoint... holds
  // its bound).
  tool.contact = ToolContact::Points;
  auto backend = make_cpu_backend(model, tool, {});
  TickRequest request;
  request.dt = 1e-6;
  request.substeps = 1;
  request.tool_active = true;
  request.tool_from = request.tool_to = centre;
  const Reaction r = backend->tick(request);
  ASSERT_EQ(r.contacts, 1);
  // Reaction = k_c s (R - |x - c|) along the diagonal; 1e-9: rounding.
  const double expected = 1000 * model.tool_k_scale[corner] * depth;
  EXPECT_NEAR(r.force.norm(), expected, 1e-9 * expected);
  EXPECT_LT(model.tool_k_scale[corner], 1e-2);
}

}  // namespace
}  // namespace tool_stiffness_test
}  // namespace organsim
