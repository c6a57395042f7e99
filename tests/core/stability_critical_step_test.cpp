// dt_crit before a run: exact cases, bounds, limiting points and slivers,
// the pre-run refusal, and agreement with the empirically observed threshold.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "core/stability/critical_step.h"
#include "core/util/error.h"
#include "tests/core/stability_test_util.h"

namespace organsim {
namespace stability_critical_step_test {
namespace {

// Two free equal masses on one spring: lambda = 2k/m, so dt_crit = sqrt(2m/k)
// (not 2 sqrt(m/k), which holds only with the other end fixed).
TEST(StabilityCriticalStep, TwoFreeMassesOnOneSpring) {
  const double k = 50, m = 0.02;
  const Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0.1, 0, 0)}, {m, m}, {{0, 1}}, k, 0, {});
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_TRUE(r.converged);
  EXPECT_NEAR(r.lambda_max, 2 * k / m, 1e-6 * 2 * k / m);  // single nonzero mode: exact up to rounding
  EXPECT_NEAR(r.dt_crit, std::sqrt(2 * m / k), 1e-6 * std::sqrt(2 * m / k));
  EXPECT_GE(r.lambda_gershgorin, r.lambda_max * (1 - 1e-12));
  ASSERT_FALSE(r.mode_points.empty());
  EXPECT_NEAR(r.mode_points[0].mode_share, 0.5, 1e-6);  // both masses move equally
}

// One end fixed: lambda = k/m; Gershgorin is exact for a single free point.
TEST(StabilityCriticalStep, MassOnFixedSpring) {
  const double k = 50, m = 0.02;
  const Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -0.1)}, {m, m}, {{0, 1}}, k, 0, {0});
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_NEAR(r.dt_crit, 2 * std::sqrt(m / k), 1e-6 * 2 * std::sqrt(m / k));
  EXPECT_NEAR(r.lambda_gershgorin, k / m, 1e-9 * k / m);
  EXPECT_EQ(r.free_points, 1);
  ASSERT_EQ(r.mode_points.size(), 1u);
  EXPECT_EQ(r.mode_points[0].point, 1);
}

// The damped formula against the scheme itself: with a damper d = c k and
// drag alpha, the step just under the formula's dt stays bounded and the step
// just over grows (the formula is exact for one mode, see critical_step.h).
TEST(StabilityCriticalStep, DampedStepMatchesTheIntegrator) {
  const double k = 50, m = 0.02, c = 0.004;
  Model model = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0, 0, -0.1)}, {m, m}, {{0, 1}}, k, c * k, {0});
  model.viscous_damping = 20;
  const StabilityReport r = estimate_critical_step(model);
  const double w = std::sqrt(k / m), xi = (c * w * w + 20) / (2 * w);
  EXPECT_NEAR(r.damping_ratio, xi, 1e-6 * xi);
  const double expected = (2 / w) * (std::sqrt(1 + xi * xi) - xi);
  EXPECT_NEAR(r.dt_crit, expected, 1e-6 * expected);
  EXPECT_LT(r.dt_crit, r.dt_crit_undamped);  // damping shrinks the step
  // 1 % either side: growth per step at 1.01 x is large enough to show in 3000 steps.
  EXPECT_FALSE(testing::perturbation_grows(model, 0.99 * r.dt_crit));
  EXPECT_TRUE(testing::perturbation_grows(model, 1.01 * r.dt_crit));
}

// Gershgorin is an upper bound on lambda_max, and the box's two estimates
// are within a factor of a few (the bound is not absurd).
TEST(StabilityCriticalStep, GershgorinBoundsPowerIteration) {
  const Model model = testing::stability_box(4, 0.04, testing::undamped_material(3000, 2e4), 0.2, 5);
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_TRUE(r.converged);
  EXPECT_GE(r.lambda_gershgorin, r.lambda_max);
  EXPECT_LT(r.lambda_gershgorin, 4 * r.lambda_max);
  EXPECT_LE(r.dt_crit_gershgorin, r.dt_crit);
  EXPECT_NEAR(r.share_springs + r.share_volume + r.share_tool, 1.0, 1e-9);
  EXPECT_GT(r.share_volume, 0.0);
}

// A sliver: interior point 21 of a 4x4x4 lattice moved 0.9 of a cell
// towards its neighbour 22 (+x). Tets between them go flat and the spring
// 21-22 gets short (k = E V / r^2): the step shrinks, and the report names
// these points (input numbering) and a flat tet holding point 21.
TEST(StabilityCriticalStep, SliverIsReportedAsLimiting) {
  TetMesh mesh = make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.03), 3, 3, 3);
  const int32_t moved = 21, neighbour = 22;
  ASSERT_NEAR((mesh.points[moved] - Vec3(0.01, 0.01, 0.01)).norm(), 0, 1e-12);
  ASSERT_NEAR((mesh.points[neighbour] - Vec3(0.02, 0.01, 0.01)).norm(), 0, 1e-12);
  mesh.points[moved].x() += 0.009;
  const Material material = testing::undamped_material(3000, 3e4);
  const Model model = build_model(mesh, material, {});
  const StabilityReport r = estimate_critical_step(model);
  ASSERT_FALSE(r.mode_points.empty());
  for (int32_t p : {r.mode_points[0].point, r.gershgorin_points[0].point})
    EXPECT_TRUE(p == moved || p == neighbour) << "limiting point " << p;
  ASSERT_FALSE(r.slivers.empty());
  EXPECT_LT(r.slivers[0].quality, 0.05);  // a regular tet is 1, a Kuhn cube tet 0.27
  EXPECT_LT(r.slivers[0].min_dihedral_deg, 10.0);
  bool touches = false;
  for (int32_t p : r.slivers[0].points) touches |= p == moved;
  EXPECT_TRUE(touches);
  // The same mesh without the sliver allows a much larger step.
  const Model regular = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.03), 3, 3, 3), material, {});
  EXPECT_GT(estimate_critical_step(regular).dt_crit, 1.5 * r.dt_crit);
}

// The tool term: stiffness added to the points it may touch only.
TEST(StabilityCriticalStep, ToolContactShrinksTheStepNearItsPath) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material(), 0, 1);
  const StabilityReport without = estimate_critical_step(model);
  ToolSpec tool;
  tool.radius = 0.005;
  tool.keyframes = {{0, Vec3(0.015, 0.015, 0.04)}, {1, Vec3(0.015, 0.015, 0.025)}};
  CriticalStepOptions options;
  options.tool_contact_stiffness = 50 * without.lambda_max * model.mass[0];  // far stiffer than the springs
  options.tool_may_touch = points_near_tool_path(model, tool);
  const StabilityReport with = estimate_critical_step(model, options);
  EXPECT_GT(with.tool_points, 0);
  EXPECT_LT(with.tool_points, with.free_points);
  EXPECT_LT(with.dt_crit, 0.5 * without.dt_crit);
  EXPECT_GT(with.share_tool, 0.5);
  // Every limiting point lies near the tool path.
  for (const auto& p : with.mode_points)
    EXPECT_TRUE(options.tool_may_touch[model.internal_of_input[p.point]]) << "point " << p.point;
}

// A capsule reaches its extent beyond its origin's path in any
// orientation: the points that may feel it are those within 2 R + extent
// of the path (the sphere's rule with the shaft added), so a light point
// under the shaft, far from the tip's path, is counted in dt_crit too.
TEST(StabilityCriticalStep, CapsuleReachesItsShaftsExtentFromThePath) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material(), 0, 1);
  ToolSpec sphere;
  sphere.radius = 0.003;
  sphere.contact = ToolContact::Points;
  sphere.keyframes = {{0, Vec3(0.015, 0.015, 0.035)}};
  ToolSpec capsule = sphere;
  capsule.shape = ToolShape::Capsule;
  capsule.end_b = Vec3(0, 0, 0.02);
  const std::vector<uint8_t> near_sphere = points_near_tool_path(model, sphere);
  const std::vector<uint8_t> near_capsule = points_near_tool_path(model, capsule);
  int sphere_count = 0, capsule_count = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    const double d = (model.rest_position[i] - sphere.keyframes[0].position).norm();
    EXPECT_EQ(near_sphere[i] != 0, d <= 2 * sphere.radius) << "point " << i;
    EXPECT_EQ(near_capsule[i] != 0, d <= 2 * capsule.radius + 0.02) << "point " << i;
    sphere_count += near_sphere[i];
    capsule_count += near_capsule[i];
  }
  EXPECT_GT(capsule_count, sphere_count);
}

// Refusal keeps the haptic tick and names dt_crit; --allow-unstable warns.
TEST(StabilityCriticalStep, CheckRefusesAndSuggestsSameTick) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material(), 0, 1);
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_EQ(check_time_step(r, 0.9 * r.dt_crit, 10, false), "");
  const double dt = 1.5 * r.dt_crit;
  try {
    check_time_step(r, dt, 10, false);
    FAIL() << "expected a refusal";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("dt_crit"), std::string::npos) << msg;
    EXPECT_NE(msg.find("--allow-unstable"), std::string::npos) << msg;
  }
  EXPECT_NE(check_time_step(r, dt, 10, true).find("warning"), std::string::npos);
  const StepSuggestion s = suggest_step(r, dt * 10);
  EXPECT_NEAR(s.dt * s.substeps, dt * 10, 1e-12 * dt);  // same tick
  EXPECT_LE(s.dt, 0.9 * r.dt_crit * (1 + 1e-12));
  EXPECT_EQ(s.substeps, static_cast<int32_t>(std::ceil(dt * 10 / (0.9 * r.dt_crit))));
  const nlohmann::json j = to_json(r);
  EXPECT_DOUBLE_EQ(j["dt_crit"].get<double>(), r.dt_crit);
  EXPECT_FALSE(format_stability_report(r, dt, 10).empty());
}

// Issue 5: predicted dt_crit within 25 % of the empirical threshold on two
// undamped models. In practice the agreement is far better (power iteration
// converges to < 1e-5; a bisection showed the threshold within 0.2 %): we
// assert 3 %, which fails if a stiffness term were missing or doubled. The
// threshold is within 3 % exactly when a perturbation stays bounded at
// 0.97 dt_crit and grows at 1.03 dt_crit (growth is monotone in dt), so two
// runs decide it.
void expect_prediction_matches(const Model& model) {
  const StabilityReport r = estimate_critical_step(model);
  ASSERT_TRUE(r.converged);
  EXPECT_FALSE(testing::perturbation_grows(model, 0.97 * r.dt_crit)) << "dt_crit " << r.dt_crit << " s";
  EXPECT_TRUE(testing::perturbation_grows(model, 1.03 * r.dt_crit)) << "dt_crit " << r.dt_crit << " s";
}

TEST(StabilityCriticalStep, PredictionMatchesObservedThresholdBox) {
  expect_prediction_matches(testing::stability_box(4, 0.04, testing::undamped_material()));
}

TEST(StabilityCriticalStep, PredictionMatchesObservedThresholdJitteredWithVolume) {
  expect_prediction_matches(testing::stability_box(4, 0.04, testing::undamped_material(3000, 3e4), 0.3, 9));
}

}  // namespace
}  // namespace stability_critical_step_test
}  // namespace organsim
