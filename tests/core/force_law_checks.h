#pragma once
// Checks shared by the tests of a force-law term (the nodal volume term, the
// shear element): a deformed moving state, one step of the reference
// backend and of the kernel against Verlet on the double reference force,
// and the scatter step against the reference backend.
#include <gtest/gtest.h>

#include <random>

#include "core/model/model.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "core/sim/scatter_step.h"
#include "tests/core/test_models.h"

namespace organsim::testing {

// The soft material of the force-law tests: E = 4 kPa, the given Poisson
// ratio, springs damped at 10 ms and drag of 2 / s.
inline Material soft_material(double nu) {
  Material m;
  m.density = 1000;
  m.young_modulus = 4000;
  m.poisson_ratio = nu;
  m.spring_damping_time = 0.01;
  m.viscous_damping = 2;
  return m;
}

// A deformed, moving state: displacements ~1 mm on a 5 cm box, rounded to
// float so that both precisions start from the same positions.
inline void random_state(const Model& model, unsigned seed, double dt, std::vector<Vec3>& x,
                         std::vector<Vec3>& x_prev) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 1);
  x = model.rest_position;
  x_prev.resize(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] += (1e-3 * Vec3(noise(rng), noise(rng), noise(rng))).cast<float>().cast<double>();
    x_prev[i] = x[i] - (dt * 0.2 * Vec3(noise(rng), noise(rng), noise(rng))).cast<float>().cast<double>();
  }
}

// One step of dt on `backend` from (x, x_prev) against position Verlet
// with the double reference force: the largest position difference and
// the largest force increment dt^2 |f|_max / m_i, m.
struct StepError {
  double worst = 0, largest = 0;
};
inline StepError step_error(Backend& backend, const Model& model, const std::vector<Vec3>& x,
                            const std::vector<Vec3>& x_prev, double dt) {
  std::vector<Vec3> v(x.size()), force;
  for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev[i]) / dt;
  reference_internal_forces(model, x, v, force);
  double scale = 0;
  for (const Vec3& f : force) scale = std::max(scale, f.norm());
  backend.set_state(x, x_prev);
  run_ticks(backend, 1, dt, 1);
  std::vector<Vec3> after;
  backend.positions(after);
  StepError e;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    const Vec3 expected = model.fixed[i] ? x[i]
                                         : Vec3(x[i] + (1 - model.viscous_damping * dt) * (x[i] - x_prev[i]) +
                                                dt * dt * model.inv_mass[i] * force[i]);
    e.worst = std::max(e.worst, (after[i] - expected).norm());
    e.largest = std::max(e.largest, dt * dt * model.inv_mass[i] * scale);
  }
  return e;
}
// The same on the reference backend (Verlet) and on the CPU backend's
// kernel (its default target, one thread) in `precision`.
inline StepError reference_step_error(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev,
                                      double dt) {
  return step_error(*make_reference_backend(model, {}, Integrator::Verlet), model, x, x_prev, dt);
}
inline StepError kernel_step_error(const Model& model, const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev,
                                   double dt, Precision precision) {
  return step_error(*make_cpu_backend(model, {}, {precision, 1}), model, x, x_prev, dt);
}

// The reference backend's step and the kernel's (double and float) against
// Verlet on the reference force, from random_state(seed) for seeds 1 and 2
// and chunk sizes 64 and 16 (padding, lane groups; 16 is the widest
// target's float register) of make_model(seed, chunk). Double: the same
// terms summed in another order, ~1e-12 of the force increment. Float:
// positions carry ~6e-8 relative rounding, i.e. ~3e-9 m on 5 cm against
// 1 mm deformations, ~1e-5 of the force, plus the rounding of x itself
// (~4e-9 m); tolerance 1e-4 of the largest increment plus 1e-8 m.
template <class MakeModel>
inline void expect_steps_match_the_reference_force(MakeModel make_model) {
  const double dt = 1e-4;
  for (unsigned seed : {1u, 2u}) {
    for (int32_t chunk : {64, 16}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " chunk " + std::to_string(chunk));
      const Model model = make_model(seed, chunk);
      std::vector<Vec3> x, x_prev;
      random_state(model, seed, dt, x, x_prev);
      const StepError r = reference_step_error(model, x, x_prev, dt);
      EXPECT_LT(r.worst, 1e-15 + 1e-12 * r.largest) << "reference";
      for (Precision precision : {Precision::Double, Precision::Float}) {
        const StepError e = kernel_step_error(model, x, x_prev, dt, precision);
        const bool dbl = precision == Precision::Double;
        EXPECT_LT(e.worst, dbl ? 1e-15 + 1e-12 * e.largest : 1e-8 + 1e-4 * e.largest) << (dbl ? "double" : "float");
      }
    }
  }
}

// `steps` steps of dt from rest of the scatter step and the reference
// backend, both double: the largest difference between them and the
// largest motion, m.
struct PathDifference {
  double worst = 0, motion = 0;
};
inline PathDifference scatter_against_reference(const Model& model, int steps, double dt) {
  ScatterStep<double> scatter(model);
  auto backend = make_reference_backend(model, {}, Integrator::Verlet);
  for (int s = 0; s < steps; ++s) scatter.step(dt);
  run_ticks(*backend, steps, dt, 1);
  std::vector<Vec3> a, b;
  scatter.positions(a);
  backend->positions(b);
  PathDifference d;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    d.motion = std::max(d.motion, (a[i] - model.rest_position[i]).norm());
    d.worst = std::max(d.worst, (a[i] - b[i]).norm());
  }
  return d;
}

}  // namespace organsim::testing
