// The averaged nodal volume term (Model::point_volume_k, docs/physics.md):
// its energy and forces, the reference backend, the CPU kernel and the
// scatter step against the double reference force, the rest state, topology rebuilds, and dt_crit
// against the integrator. The simd kernel's nodal term is tested with
// the kernels (cpu_kernel_test.cpp, cpu_kernel_double_test.cpp).
#include <gtest/gtest.h>

#include "core/model/nodal_volume.h"
#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "tests/core/force_law_checks.h"
#include "tests/core/stability_test_util.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace nodal_volume_test {
namespace {

Material nodal_material(double nu = 0.45) { return testing::soft_material(nu); }

Model nodal_model(unsigned seed, int cells, int32_t chunk = kDefaultChunkSize, const Vec3& gravity = Vec3::Zero()) {
  return build_model(testing::jittered_box(cells, 0.05, 0.25, seed), nodal_material(),
                     testing::fixed_bottom_options(gravity, chunk));
}

TEST(NodalVolume, PoissonRatioSelectsItAndVolumeModulusKeepsThePerTetTerm) {
  const Model nodal = nodal_model(1, 3);
  EXPECT_TRUE(nodal.has_nodal_volume());
  EXPECT_TRUE(nodal.tet_k.empty());
  Material old = nodal_material();
  old.poisson_ratio.reset();
  old.volume_modulus = 20000;
  const Model per_tet = build_model(testing::jittered_box(3, 0.05, 0.25, 1), old, {});
  EXPECT_FALSE(per_tet.has_nodal_volume());
  EXPECT_EQ(per_tet.ntet(), static_cast<int32_t>(per_tet.tet_k.size()));
  // Explicit choice either way.
  Material explicit_tet = nodal_material();
  explicit_tet.volume_formulation = VolumeFormulation::PerTet;
  EXPECT_FALSE(build_model(testing::jittered_box(3, 0.05, 0.25, 1), explicit_tet, {}).has_nodal_volume());
  old.volume_formulation = VolumeFormulation::Nodal;
  EXPECT_TRUE(build_model(testing::jittered_box(3, 0.05, 0.25, 1), old, {}).has_nodal_volume());
}

// Under an affine deformation every tet's volume scales by det F, so every
// nodal volume does too, and the nodal energy equals the per-tet one:
// K/2 V (det F - 1)^2. This is why the same K = lambda - mu serves both
// (docs/physics.md). 1e-9: rounding of sums of ~300 tets.
TEST(NodalVolume, AffineDeformationStoresThePerTetEnergy) {
  Material m = nodal_material();
  m.young_modulus = 1e-9;  // springs negligible: the energy is the volume term's
  const TetMesh mesh = testing::jittered_box(4, 0.05, 0.25, 3);
  const Model nodal = build_model(mesh, m, {});
  m.volume_formulation = VolumeFormulation::PerTet;
  const Model per_tet = build_model(mesh, m, {});
  Eigen::Matrix3d F;
  F << 1.002, 0.001, 0, 0.0005, 0.999, 0.0003, 0, 0.0002, 1.001;
  std::vector<Vec3> x(nodal.npoint());
  for (int32_t i = 0; i < nodal.npoint(); ++i) x[i] = F * nodal.rest_position[i];
  const double J = F.determinant();
  const double expected = 0.5 * volume_term_modulus(m) * nodal.rest_volume() * (J - 1) * (J - 1);
  double springs = 0;
  for (int32_t s = 0; s < nodal.nspring(); ++s) {
    const auto [a, b] = nodal.spring_ends[s];
    const double stretch = (x[b] - x[a]).norm() - nodal.spring_rest[s];
    springs += 0.5 * nodal.spring_k[s] * stretch * stretch;
  }
  EXPECT_NEAR(elastic_energy(nodal, x) - springs, expected, 1e-9 * expected);
  EXPECT_NEAR(elastic_energy(per_tet, x) - springs, expected, 1e-9 * expected);
}

// The reference force is minus the gradient of the energy (the term is
// conservative). Central differences with h = 1e-8 m on a 1 mm deformation:
// truncation ~h^2 / (1 mm)^2 = 1e-10 relative, rounding ~1e-16 E / h; 1e-6
// of the largest force covers both.
TEST(NodalVolume, ReferenceForceIsMinusTheEnergyGradient) {
  Model model = nodal_model(2, 3);
  std::vector<Vec3> x, x_prev;
  testing::random_state(model, 7, 1e-4, x, x_prev);
  std::vector<Vec3> force, zero(x.size(), Vec3::Zero());
  reference_internal_forces(model, x, zero, force);
  double scale = 0;
  for (const Vec3& f : force) scale = std::max(scale, f.norm());
  const double h = 1e-8;
  for (int32_t i = 0; i < model.npoint(); i += 7) {
    for (int k = 0; k < 3; ++k) {
      std::vector<Vec3> plus = x, minus = x;
      plus[i][k] += h;
      minus[i][k] -= h;
      const double gradient = (elastic_energy(model, plus) - elastic_energy(model, minus)) / (2 * h);
      EXPECT_NEAR(force[i][k], -gradient, 1e-6 * scale) << "point " << i << " axis " << k;
    }
  }
}

// The reference backend and the kernel against Verlet on the reference
// force: one step from a deformed, moving state, for two chunk sizes
// (padding, lane groups).
TEST(NodalVolume, StepsMatchTheReferenceForceOnRandomMeshes) {
  testing::expect_steps_match_the_reference_force(
      [](unsigned seed, int32_t chunk) { return nodal_model(seed, 5, chunk, Vec3(0.3, -1, -9.81)); });
}

// At rest every nodal pressure is exactly zero in either precision: the
// kernel computes the rest nodal volumes with the same instructions as the
// step. 1000 steps from rest without gravity must not move a single bit.
TEST(NodalVolume, RestStateIsExactlyForceFree) {
  const Model model = nodal_model(4, 5);
  for (Precision precision : {Precision::Double, Precision::Float}) {
    auto backend = make_cpu_backend(model, {}, {precision, 1});
    testing::run_ticks(*backend, 100, 1e-4, 10);
    std::vector<Vec3> x;
    backend->positions(x);
    double moved = 0;
    for (int32_t i = 0; i < model.npoint(); ++i) moved = std::max(moved, (x[i] - model.rest_position[i]).norm());
    EXPECT_EQ(moved, 0.0) << (precision == Precision::Double ? "double" : "float");
  }
}

// The plain scatter step that bench times runs the same physics: 200 steps
// of both in double from the same deformed state agree to rounding.
TEST(NodalVolume, ScatterStepMatchesTheReference) {
  const Model model = nodal_model(5, 4, kDefaultChunkSize, Vec3(0, 0, -9.81));
  const testing::PathDifference d = testing::scatter_against_reference(model, 200, 1e-4);
  ASSERT_GT(d.motion, 1e-6);
  // Different summation order over 200 steps: ~1e-12 of the motion.
  EXPECT_LT(d.worst, 1e-9 * d.motion);
}

// A cut splits node patches: the rebuilt Model's nodal rest volumes come
// from the new tets (the copies share their origin's volume, the total is
// kept), and the backend rebuilt from it is still exactly at rest.
TEST(NodalVolume, RebuildRecomputesNodalRestVolumes) {
  Material m = nodal_material();
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), m, {});
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.02));
  ASSERT_GT(cut.npoint(), model.npoint());
  ASSERT_TRUE(cut.has_nodal_volume());
  double before = 0, after = 0;
  for (double v : model.point_rest_volume) before += v;
  for (double v : cut.point_rest_volume) after += v;
  EXPECT_NEAR(after, before, 1e-15);  // the same tet quarters, regrouped
  for (int32_t p = model.npoint(); p < cut.npoint(); ++p) {
    const int32_t o = cut.origin[p];
    EXPECT_NEAR(cut.point_rest_volume[p] + cut.point_rest_volume[o], model.point_rest_volume[o], 1e-18) << p;
    EXPECT_LT(cut.point_rest_volume[o], model.point_rest_volume[o]) << o;
  }
  auto backend = make_cpu_backend(model, {}, {Precision::Float, 1});
  backend->rebuild(cut);
  testing::run_ticks(*backend, 20, 1e-4, 5);
  std::vector<Vec3> x;
  backend->positions(x);
  for (int32_t i = 0; i < cut.npoint(); ++i) EXPECT_EQ(x[i], cut.rest_position[i]) << i;
}

// dt_crit includes the nodal term: just under it a perturbation stays
// bounded, just over it grows (the estimate is the scheme's own threshold).
// Undamped, nu = 0.45: the volume term is most of the top mode.
TEST(NodalVolume, CriticalStepIncludesTheNodalTerm) {
  Material m = testing::undamped_material(3000);
  m.poisson_ratio = 0.45;
  const Model model = testing::stability_box(3, 0.03, m, 0.2, 5);
  ASSERT_TRUE(model.has_nodal_volume());
  const StabilityReport r = estimate_critical_step(model);
  EXPECT_TRUE(r.converged);
  EXPECT_GE(r.lambda_gershgorin, r.lambda_max);
  EXPECT_GT(r.share_volume, 0.5);
  // 2 % either side: enough growth per step to show in 3000 steps.
  EXPECT_FALSE(testing::perturbation_grows(model, 0.98 * r.dt_crit));
  EXPECT_TRUE(testing::perturbation_grows(model, 1.02 * r.dt_crit));
}

}  // namespace
}  // namespace nodal_volume_test
}  // namespace organsim
