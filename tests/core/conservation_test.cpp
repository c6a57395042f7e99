// Physical invariants of the free model: momentum, centre of mass, volume.
#include <gtest/gtest.h>

#include <random>

#include "core/sim/cpu_backend.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace conservation_test {
namespace {

Model free_box_model(double volume_modulus, double viscous) {
  Material material;
  material.density = 1000;
  material.young_modulus = 5000;
  material.volume_modulus = volume_modulus;
  material.viscous_damping = viscous;
  return build_model(testing::jittered_box(4, 0.05, 0.2, 7), material, {});
}

Vec3 momentum(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev, double dt) {
  Vec3 p = Vec3::Zero();
  for (int i = 0; i < model.npoint(); ++i) p += model.mass[i] * (x[i] - x_prev[i]) / dt;
  return p;
}

Vec3 centre_of_mass(const Model& model, const std::vector<Vec3>& x) {
  Vec3 c = Vec3::Zero();
  for (int i = 0; i < model.npoint(); ++i) c += model.mass[i] * x[i];
  return c / model.total_mass();
}

TEST(Conservation, FreeModelKeepsMomentumAndCentreOfMassPath) {
  // Springs, dampers and the volume term are internal forces summing to
  // zero, and Verlet updates momentum by dt * sum F: it is kept to rounding.
  const Model model = free_box_model(20000, 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 1);
  const double dt = 1e-5;
  std::vector<Vec3> x = model.rest_position, x_prev(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] += 1e-3 * Vec3(noise(rng), noise(rng), noise(rng));  // deformed
    x_prev[i] = x[i] - dt * Vec3(0.1 + 0.05 * noise(rng), 0.05 * noise(rng), 0.05 * noise(rng));  // moving
  }
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  backend->set_state(x, x_prev);
  const Vec3 p0 = momentum(model, x, x_prev, dt);
  const Vec3 c0 = centre_of_mass(model, x);
  testing::run_ticks(*backend, 100, dt, 20);  // 2000 steps, 20 ms
  std::vector<Vec3> x_end, x_before;
  backend->positions(x_end);
  // Momentum at the end from one more step's displacement.
  x_before = x_end;
  testing::run_ticks(*backend, 1, dt, 1);
  std::vector<Vec3> x_after;
  backend->positions(x_after);
  const Vec3 p1 = momentum(model, x_after, x_before, dt);
  // Relative 1e-9: thousands of steps of double rounding on forces that
  // cancel pairwise.
  EXPECT_LT((p1 - p0).norm(), 1e-9 * p0.norm());
  // The centre of mass moves uniformly: c(t) = c0 + p0/M t.
  const Vec3 c1 = centre_of_mass(model, x_after);
  const double t = backend->time();
  EXPECT_LT((c1 - (c0 + p0 / model.total_mass() * t)).norm(), 1e-10);  // m, for a 5 cm model
}

TEST(Conservation, ModelAtRestStaysAtRest) {
  const Model model = free_box_model(20000, 1.0);
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  testing::run_ticks(*backend, 50, 1e-4, 10);
  std::vector<Vec3> x;
  backend->positions(x);
  // Rest lengths are exact; rest volumes are recomputed in another vertex
  // order, so the volume term sees ~1e-16 relative residuals: 1e-14 m.
  for (int i = 0; i < model.npoint(); ++i)
    EXPECT_LT((x[i] - model.rest_position[i]).norm(), 1e-14) << "point " << i;
}

}  // namespace
}  // namespace conservation_test
}  // namespace organsim
