// The GL backend with the shear element of nu < 1/4 (step.comp's
// SHEAR_ELEMENT variant, smoothed by default: shear_smoothing.comp and
// SMOOTHED_SHARE) against the double CPU reference: the force of one
// step on a deformed box, its damper's, and 1000 steps of a box released
// from a shear.
#include <gtest/gtest.h>

#include <random>

#include "core/gl/gl_backend.h"
#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace {

constexpr double kDt = 1e-4;  // s

// Both forms (per tet; smoothed, with shear_smoothing.comp first), with 1, 3
// and 8 invocations per point (THREADS_PER_POINT, kernel_test.cpp).
TEST(GlShearElement, ForceMatchesTheReference) {
  for (ShearFormulation form : {ShearFormulation::Smoothed, ShearFormulation::PerTet}) {
  for (double nu : {0.0, 0.15}) {
   for (const int32_t threads_per_point : {1, 3, 8}) {
    // The shared soft box: springs carry lambda, the element mu - lambda (all of it at nu = 0).
    const Model model = gl_test::poisson_box(nu, Vec3(0, 0, -9.81), Material{}.spring_damping_time, form);
    ASSERT_TRUE(model.has_shear_element());
    ASSERT_EQ(model.has_smoothed_shear(), form == ShearFormulation::Smoothed);
    const double error =
        gl_test::one_substep_force_error(model, gl_test::moving_state(model, kDt), kDt, threads_per_point);
    std::cout << "shear element (" << shear_formulation_name(form) << ") nu " << nu << ", " << threads_per_point
              << " invocation(s) per point: max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
    // Float: the displacements x - X (1 mm) carry the rounding of x (~4e-9
    // m near 0.1 m), a few 1e-6 of a displacement difference, and the
    // springs as in kernel_test.cpp (measured 7e-7 of the largest force); a
    // wrong index, sign, transpose or factor gives errors of order 1.
    // Tolerance 1e-5, as for the nodal term.
    EXPECT_LT(error, 1e-5) << shear_formulation_name(form) << " nu " << nu << ", " << threads_per_point << " per point";
   }
  }
  }
}

// Crushed along z to 0.7 and 0.3 of its height (the second below
// kShearElementMinJ, on the barrier's quadratic extension): the same force
// as the reference. Tolerance as above; the crushed tets' forces are large,
// and the float rounding relative to them is no worse.
TEST(GlShearElement, CrushedForceMatchesTheReference) {
  const Model model = gl_test::poisson_box(0.0, Vec3::Zero());
  for (double s : {0.7, 0.3}) {
    gl_test::MovingState state;
    state.x = model.rest_position;
    for (Vec3& p : state.x) p.z() *= s;
    state.x = gl_test::round_to_float(state.x);
    state.x_prev = state.x;
    state.v.assign(state.x.size(), Vec3::Zero());
    const double error = gl_test::one_substep_force_error(model, state, kDt);
    std::cout << "shear element crushed to " << s << ": max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
    EXPECT_LT(error, 1e-5) << "stretch " << s;
  }
}

// The element's damper (tau = 10 ms) against the reference where it carries
// most of the force: the moving state with velocities ~0.2 m/s, and the
// same velocities on the box crushed to 0.3 of its height (J < J_min, the
// clamped 1 / J_d). The increments d = x_t - x_{t-1} (~2e-5 m) are
// differences of float positions, exact in float, so the tolerance is that
// of the force above.
TEST(GlShearElement, DamperForceMatchesTheReference) {
  const Model model = gl_test::poisson_box(0.0, Vec3::Zero(), 0.01);
  ASSERT_GT(model.shear_damping_time, 0);
  gl_test::MovingState moving = gl_test::moving_state(model, kDt);
  gl_test::MovingState crushed = moving;
  for (Vec3& p : crushed.x) p.z() *= 0.3;
  crushed.x = gl_test::round_to_float(crushed.x);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 0.2 * kDt);
  for (gl_test::MovingState* s : {&moving, &crushed}) {
    for (size_t i = 0; i < s->x.size(); ++i) s->x_prev[i] = s->x[i] - Vec3(noise(rng), noise(rng), noise(rng));
    s->x_prev = gl_test::round_to_float(s->x_prev);
    for (size_t i = 0; i < s->x.size(); ++i) s->v[i] = (s->x[i] - s->x_prev[i]) / kDt;
    // The damper's share of the reference force: most of it.
    std::vector<Vec3> with, without, zero(s->x.size(), Vec3::Zero());
    reference_internal_forces(model, s->x, s->v, with);
    reference_internal_forces(model, s->x, zero, without);
    double damper = 0, total = 0;
    for (size_t i = 0; i < with.size(); ++i) {
      damper = std::max(damper, (with[i] - without[i]).norm());
      total = std::max(total, with[i].norm());
    }
    EXPECT_GT(damper, 0.5 * total);
    for (const int32_t threads_per_point : {1, 3}) {
      const double error = gl_test::one_substep_force_error(model, *s, kDt, threads_per_point);
      std::cout << "shear element damper" << (s == &crushed ? " (crushed)" : "") << ", damper share "
                << damper / total << ": max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
      EXPECT_LT(error, 1e-5) << threads_per_point << " per point";
    }
  }
}

// 1000 steps (100 ticks x 10) of the box released from a 2 % simple shear
// under gravity, so the element drives the motion: GL against the CPU double
// reference within 1e-5 of the bounding-box diagonal, the tolerance and
// reasoning of parity_test.cpp (float positions random-walk ~1e-6 of the
// diagonal; a wrong or missing element moves points by millimetres).
TEST(GlShearElement, TrajectoryMatchesTheCpuReference) {
  const Model model = gl_test::poisson_box(0.05, Vec3(0, 0, -9.81));
  std::vector<Vec3> sheared = model.rest_position;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) sheared[i].x() += 0.02 * sheared[i].z();
  sheared = gl_test::round_to_float(sheared);
  const gl_test::TrajectoryDifference d = gl_test::cpu_and_gl_from(model, sheared, kDt, 100);
  const double diagonal = gl_test::bbox_diagonal(model);
  std::cout << "shear element trajectory: max |x_gl - x_cpu| / diagonal = " << d.worst / diagonal << ", motion "
            << d.motion << " m\n";
  ASSERT_GT(d.motion, 1e-4);  // it moved: a missing term would show
  EXPECT_LT(d.worst, 1e-5 * diagonal);
}

}  // namespace
}  // namespace organsim
