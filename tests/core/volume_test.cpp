// The volume conservation force: direction, and what it buys under squeezing.
#include <gtest/gtest.h>

#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace volume_test {
namespace {

double deformed_volume(const Model& model, const std::vector<Vec3>& x) {
  double v = 0;
  for (const Tet& t : model.tet_points) v += signed_volume(x[t[0]], x[t[1]], x[t[2]], x[t[3]]);
  return v;
}

TEST(Volume, CompressedTetPushesBackAlongVolumeGradient) {
  TetMesh mesh;
  mesh.points = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0), Vec3(0, 0, 0.01)};
  mesh.tets = {{0, 1, 2, 3}};
  Material material;
  material.spring_stiffness = 1e-12;  // N/m: springs negligible, volume term alone
  material.spring_damping_time = 0;
  material.viscous_damping = 0;
  material.volume_modulus = 1e4;
  const Model model = build_model(mesh, material, {});
  // Push the apex (input point 3) halfway down towards the opposite face z = 0.
  const int32_t apex = model.internal_of_input[3];
  std::vector<Vec3> x = model.rest_position;
  x[apex].z() = 0.005;
  const std::vector<Vec3> v(x.size(), Vec3::Zero());
  std::vector<Vec3> expected;
  reference_internal_forces(model, x, v, expected);
  // Analytic: V = V_r / 2, dV/dx_apex = area(base)/3 * e_z, f = k_v (V_r - V) dV/dx.
  const double rest = 1e-6 / 6, area = 0.5e-4;
  const double k_v = 1e4 / rest;
  EXPECT_NEAR(expected[apex].z(), k_v * (rest / 2) * area / 3, 1e-9 * k_v * rest * area);
  EXPECT_NEAR(expected[apex].x(), 0, 1e-12);
  EXPECT_NEAR(expected[apex].y(), 0, 1e-12);

  // The backend applies the same force: one step from rest, x_next - x = dt^2 F / m.
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  backend->set_state(x, x);
  const double dt = 1e-5;
  testing::run_ticks(*backend, 1, dt, 1);
  std::vector<Vec3> after;
  backend->positions(after);
  for (int i = 0; i < model.npoint(); ++i) {
    const Vec3 force = model.mass[i] * (after[i] - x[i]) / (dt * dt);
    // 1e-6 relative: the position increment is ~1e-9 of the coordinates,
    // so double rounding of x leaves ~1e-7 relative in the recovered force.
    EXPECT_LT((force - expected[i]).norm(), 1e-6 * expected[apex].norm()) << "point " << i;
  }
}

// Presses a wide sphere 15 % into the top of a box fixed at its base and
// returns the relative volume change once settled.
double squeezed_volume_error(double volume_modulus) {
  const double size = 0.04;
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(size, size, size), 5, 5, 5);
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.volume_modulus = volume_modulus;
  material.viscous_damping = 60;
  ModelOptions options;
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  const Model model = build_model(mesh, material, options);
  BackendTool tool{true, ToolMode::Push, 2 * size, 2000};
  auto backend = make_cpu_backend(model, tool, testing::one_thread());
  const Vec3 start(size / 2, size / 2, size + 2 * size), end = start - Vec3(0, 0, 0.15 * size);
  TickRequest request;
  request.dt = 2e-5;
  request.substeps = 50;
  request.tool_active = true;
  const int ramp = 200, hold = 300;  // ticks of 1 ms
  for (int i = 0; i < ramp + hold; ++i) {
    const double a = std::min(1.0, static_cast<double>(i) / ramp), b = std::min(1.0, (i + 1.0) / ramp);
    request.tool_from = start + a * (end - start);
    request.tool_to = start + b * (end - start);
    backend->tick(request);
  }
  std::vector<Vec3> x;
  backend->positions(x);
  return std::abs(deformed_volume(model, x) - model.rest_volume()) / model.rest_volume();
}

TEST(Volume, SqueezingKeepsVolumeWithinBound) {
  const double without = squeezed_volume_error(0);
  const double with = squeezed_volume_error(50 * 5000);  // K = 50 E
  // Without the term the lattice (Poisson ratio ~1/4) loses several percent;
  // with K = 50 E the loss must stay under 1 % and be at least 3x smaller.
  EXPECT_GT(without, 0.02);
  EXPECT_LT(with, 0.01);
  EXPECT_LT(with * 3, without);
}

}  // namespace
}  // namespace volume_test
}  // namespace organsim
