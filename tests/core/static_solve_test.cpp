// The small-strain static solve (core/validation/static_solve.h) against the
// dynamic CPU backend relaxed to rest, and against a hand-solved spring.
#include <gtest/gtest.h>

#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/util/error.h"
#include "core/validation/static_solve.h"
#include "tests/core/stability_test_util.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace static_solve_test {
namespace {

TEST(StaticSolve, SpringPulledAtOneEndGivesHookesReaction) {
  // Two points 1 cm apart, k = 50 N/m, point 0 fixed, point 1 moved 1 mm
  // along the spring: the support must push back with k * 1 mm.
  const Model m = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0.01, 0, 0)}, {1, 1}, {{0, 1}}, 50, 0, {0});
  StaticProblem problem;
  for (int a = 0; a < 3; ++a) problem.prescribed.push_back({1, a, a == 0 ? 1e-3 : 0.0});
  const StaticSolution s = solve_static(m, problem);
  EXPECT_NEAR(s.reaction[1].x(), 50 * 1e-3, 1e-12);
  EXPECT_NEAR(s.reaction[0].x(), -50 * 1e-3, 1e-12);  // the fixed point holds the other end
}

TEST(StaticSolve, UnheldRigidMotionIsReported) {
  const Model m = testing::make_spring_model({Vec3(0, 0, 0), Vec3(0.01, 0, 0)}, {1, 1}, {{0, 1}}, 50, 0, {});
  EXPECT_THROW(solve_static(m, StaticProblem{}), Error);
}

// A 4 cm block held at its base sags under a weak gravity (0.2 m/s^2, so
// strains stay ~1e-4 and the springs' geometric nonlinearity is ~1e-4 of the
// answer). Heavy drag brings the dynamic run to rest; the static solve of
// the linearised force law (springs and the volume term, per tet or nodal)
// must give the same displacement within 1 % of its largest value.
class StaticSolveRelaxed : public ::testing::TestWithParam<VolumeFormulation> {};

TEST_P(StaticSolveRelaxed, MatchesTheCpuBackendRelaxedUnderGravity) {
  Material material;
  material.volume_formulation = GetParam();
  material.density = 1000;
  material.young_modulus = 5000;
  material.poisson_ratio = 0.4;  // with a volume term
  material.spring_damping_time = 0;
  material.viscous_damping = 300;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -0.2);
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-6);
  base.normal = Vec3(0, 0, -1);
  options.fixed = {base};
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), material, options);

  StaticProblem problem;
  problem.load.resize(model.npoint());
  for (int32_t p = 0; p < model.npoint(); ++p) problem.load[p] = model.mass[p] * options.gravity;
  const StaticSolution s = solve_static(model, problem);

  auto backend = make_cpu_backend(model, BackendTool{}, testing::one_thread());
  testing::run_ticks(*backend, 1000, 2e-4, 10);  // 2 s: the slowest mode decays by e^-50
  std::vector<Vec3> x;
  backend->positions(x);
  double largest = 0, worst = 0;
  for (int32_t p = 0; p < model.npoint(); ++p) {
    largest = std::max(largest, s.displacement[p].norm());
    worst = std::max(worst, (x[p] - model.rest_position[p] - s.displacement[p]).norm());
  }
  ASSERT_GT(largest, 1e-6);
  EXPECT_LT(worst, 0.01 * largest) << "largest static displacement " << largest << " m";
  // And the supports carry the weight.
  double held = 0;
  for (const Vec3& r : s.reaction) held += r.z();
  EXPECT_NEAR(held, 0.2 * model.total_mass(), 1e-9);
}

// The springs enter the factored stiffness by the Woodbury identity. A
// stiff spring on one coordinate must act as that coordinate prescribed:
// k = 1000x the point's diagonal stiffness gives way by less than 1e-3 of
// the push, so displacements and its force (the support's reaction) agree
// to 1e-3; a surface spring with all its weight on one corner is that
// point's spring.
TEST(StaticSolve, StiffSpringsAddedToTheFactorActAsPrescribedCoordinates) {
  Material material = testing::undamped_material(5000);
  material.poisson_ratio = 0.45;
  const Model model = testing::stability_box(3, 0.04, material);  // bottom face held
  int32_t top = 0;  // the corner (0.04, 0.04, 0.04)
  for (int32_t p = 0; p < model.npoint(); ++p)
    if (model.rest_position[p].sum() > model.rest_position[top].sum()) top = p;
  ASSERT_NEAR(model.rest_position[top].z(), 0.04, 1e-12);
  const double push = -1e-3;

  StaticProblem prescribed;
  prescribed.prescribed.push_back({top, 2, push});
  const StaticSolution want = solve_static(model, prescribed);

  const StaticSolver solver(model, {});
  const double k = 1e3 * stiffness_diagonal(model)[top];
  StaticProblem by_point;
  by_point.point_springs.push_back({top, Vec3(0, 0, 1), k, push});
  StaticProblem by_surface;
  by_surface.surface_springs.push_back({{top, 0, 1}, {1, 0, 0}, Vec3(0, 0, 1), k, push});
  for (const StaticProblem* problem : {&by_point, &by_surface}) {
    const StaticSolution got = solver.solve(*problem);
    double worst = 0;
    for (int32_t p = 0; p < model.npoint(); ++p)
      worst = std::max(worst, (got.displacement[p] - want.displacement[p]).norm());
    EXPECT_LT(worst, 1e-3 * std::abs(push));
    const double spring_force = k * (push - got.displacement[top].z());
    EXPECT_NEAR(spring_force, want.reaction[top].z(), 1e-3 * std::abs(want.reaction[top].z()));
  }
  // K u at the solved state (elastic_force): the supports' reaction at the
  // held coordinates and zero elsewhere (equilibrium, no load), to the
  // factorisation's round-off (1e-9 of the reaction).
  const std::vector<Vec3> elastic = solver.elastic_force(want.displacement);
  const double scale = std::abs(want.reaction[top].z());
  for (int32_t p = 0; p < model.npoint(); ++p)
    for (int a = 0; a < 3; ++a) {
      const bool held = model.fixed[p] || (p == top && a == 2);
      EXPECT_NEAR(elastic[p][a], held ? want.reaction[p][a] : 0.0, 1e-9 * scale) << "point " << p << " axis " << a;
    }
  // A problem holding other coordinates than were factored is refused.
  EXPECT_THROW(solver.solve(prescribed), Error);
}

INSTANTIATE_TEST_SUITE_P(VolumeTerms, StaticSolveRelaxed,
                         ::testing::Values(VolumeFormulation::PerTet, VolumeFormulation::Nodal),
                         [](const auto& info) { return std::string(volume_formulation_name(info.param)); });

}  // namespace
}  // namespace static_solve_test
}  // namespace organsim
