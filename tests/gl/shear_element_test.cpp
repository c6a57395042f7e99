// The GL backend with the shear element of nu < 1/4 (step.comp's
// SHEAR_ELEMENT variant, and with the default smoothed formulation
// shear_smoothing.comp and SMOOTHED_SHEAR) against the double CPU reference,
// for both formulations: the force of one step on a deformed box, crushed,
// with its damper, after a cut, and 1000 steps of a box released from a shear.
#include <gtest/gtest.h>

#include <random>

#include "core/gl/gl_backend.h"
#include "core/gl/gl_program.h"
#include "core/model/model_rebuild.h"
#include "core/model/stiffness.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"
#include "shaders/bindings.glsl.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace shear_element_test {
namespace {

constexpr double kDt = 1e-4;  // s
constexpr ShearFormulation kFormulations[] = {ShearFormulation::Smoothed, ShearFormulation::PerTet};

// With 1, 3 and 8 invocations per point (THREADS_PER_POINT, kernel_test.cpp):
// the step's and, smoothed, shear_smoothing.comp's partial sums.
TEST(GlShearElement, ForceMatchesTheReference) {
  for (const ShearFormulation formulation : kFormulations) {
    for (double nu : {0.0, 0.15}) {
      // The shared soft box: springs carry lambda, the element mu - lambda (all of it at nu = 0).
      const Model model = gl_test::poisson_box(nu, Vec3(0, 0, -9.81), Material{}.spring_damping_time, formulation);
      ASSERT_TRUE(model.has_shear_element());
      ASSERT_EQ(model.has_smoothed_shear(), formulation == ShearFormulation::Smoothed);
      for (const int32_t threads_per_point : {1, 3, 8}) {
        const double error =
            gl_test::one_substep_force_error(model, gl_test::moving_state(model, kDt), kDt, threads_per_point);
        std::cout << "shear element (" << shear_formulation_name(formulation) << ") nu " << nu << ", "
                  << threads_per_point << " invocation(s) per point: max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
        // Float: the displacements x - X (1 mm) carry the rounding of x (~4e-9
        // m near 0.1 m), a few 1e-6 of a displacement difference, and the
        // springs as in kernel_test.cpp (measured 7e-7 of the largest force); a
        // wrong index, sign, transpose or factor gives errors of order 1.
        // Tolerance 1e-5, as for the nodal term.
        EXPECT_LT(error, 1e-5) << shear_formulation_name(formulation) << ", nu " << nu << ", " << threads_per_point
                               << " per point";
      }
    }
  }
}

// The smoothed variants' blocks sit at the bindings the C++ binds, and the
// shear entry's std430 stride is gl::ShearEntry's (the shared
// shear_element.glsl declares it for both kernels).
TEST(GlShearElement, SmoothedBindingsAgreeBetweenCppAndGlsl) {
  const Model model = gl_test::poisson_box(0.0, Vec3::Zero());
  GlBackend gl(model, BackendTool{}, {});  // makes its context current
  const gl::ComputeProgram step("step.comp", {"SHEAR_ELEMENT", "SMOOTHED_SHEAR 0.5"});
  const gl::ComputeProgram smoothing("shear_smoothing.comp", {"THREADS_PER_POINT 3"});
  EXPECT_EQ(smoothing.workgroup_size()[0], ORGANSIM_GL_CHUNK * 3);
  EXPECT_EQ(step.storage_block_binding("ShearStress"), ORGANSIM_GL_B_SHEAR_STRESS);
  EXPECT_EQ(smoothing.storage_block_binding("ShearStress"), ORGANSIM_GL_B_SHEAR_STRESS);
  for (const char* block : {"XCur", "Chunks", "Tets", "Rest", "Shear"})
    EXPECT_GE(smoothing.storage_block_binding(block), 0) << block;
  EXPECT_EQ(smoothing.storage_block_binding("Rest"), ORGANSIM_GL_B_REST);
  EXPECT_EQ(smoothing.storage_block_binding("Shear"), ORGANSIM_GL_B_SHEAR);
  const GLenum stride = GL_TOP_LEVEL_ARRAY_STRIDE;
  GLint shear_stride = 0;
  glGetProgramResourceiv(smoothing.id(), GL_BUFFER_VARIABLE,
                         glGetProgramResourceIndex(smoothing.id(), GL_BUFFER_VARIABLE, "shear[0].ga"), 1, &stride, 1,
                         nullptr, &shear_stride);
  EXPECT_EQ(shear_stride, static_cast<GLint>(sizeof(gl::ShearEntry)));
  // Without SMOOTHED_SHEAR the step declares no stress block.
  EXPECT_EQ(gl::ComputeProgram("step.comp", {"SHEAR_ELEMENT"}).storage_block_binding("ShearStress"), -1);
  gl.context().check_errors("binding queries");
}

// The per-point pass runs only for the smoothed element, and the plan names it.
TEST(GlShearElement, SmoothingPassOnlyWhenSmoothed) {
  for (const ShearFormulation formulation : kFormulations) {
    const Model model = gl_test::poisson_box(0.0, Vec3::Zero(), Material{}.spring_damping_time, formulation);
    const Plan plan = GlBackend(model, BackendTool{}, {}).plan();
    const bool smoothed = formulation == ShearFormulation::Smoothed;
    EXPECT_EQ(plan.dispatches_per_step, smoothed ? 2 : 1) << shear_formulation_name(formulation);
    bool named = false;
    for (const auto& pass : plan.passes)
      named |= pass.name == "shear-smoothing" && pass.detail.find("shear_smoothing.comp") != std::string::npos;
    EXPECT_EQ(named, smoothed) << shear_formulation_name(formulation);
  }
}

// Crushed along z to 0.7 and 0.3 of its height (the second below
// force_law::kShearElementMinJ, on the barrier's quadratic extension): the same force
// as the reference. Tolerance as above; the crushed tets' forces are large,
// and the float rounding relative to them is no worse.
TEST(GlShearElement, CrushedForceMatchesTheReference) {
  for (const ShearFormulation formulation : kFormulations) {
    const Model model = gl_test::poisson_box(0.0, Vec3::Zero(), Material{}.spring_damping_time, formulation);
    for (double s : {0.7, 0.3}) {
      gl_test::MovingState state;
      state.x = model.rest_position;
      for (Vec3& p : state.x) p.z() *= s;
      state.x = gl_test::round_to_float(state.x);
      state.x_prev = state.x;
      state.v.assign(state.x.size(), Vec3::Zero());
      const double error = gl_test::one_substep_force_error(model, state, kDt);
      std::cout << "shear element (" << shear_formulation_name(formulation) << ") crushed to " << s
                << ": max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
      EXPECT_LT(error, 1e-5) << shear_formulation_name(formulation) << ", stretch " << s;
    }
  }
}

// The element's damper (tau = 10 ms) against the reference where it carries
// most of the force: the moving state with velocities ~0.2 m/s, and the
// same velocities on the box crushed to 0.3 of its height (J < J_min, the
// clamped 1 / J_d). The increments d = x_t - x_{t-1} (~2e-5 m) are
// differences of float positions, exact in float, so the tolerance is that
// of the force above. The damper is the same in both formulations; the
// default (smoothed) one runs here.
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

// A cut (Backend::rebuild) changes the tets around the cut plane and so the
// patch weights k_t / K_p: after it the force is the new model's reference
// force, which needs the shear entries and the stress buffer re-created.
// Tolerance as above.
TEST(GlShearElement, ForceAfterACutMatchesTheReference) {
  const Model model = gl_test::poisson_box(0.0, Vec3(0, 0, -9.81));
  ASSERT_TRUE(model.has_smoothed_shear());
  // x = 0.06 m is a plane of tet faces (5 cells over 0.1 m); 24 points are copied.
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.06));
  ASSERT_GT(cut.npoint(), model.npoint());
  GlBackendOptions options;
  options.record_forces = true;
  GlBackend gl(model, BackendTool{}, options);
  gl_test::forces_of_one_substep(gl, gl_test::moving_state(model, kDt), kDt);
  gl.rebuild(cut);
  const double error = gl_test::substep_force_error(gl, cut, gl_test::moving_state(cut, kDt), kDt);
  std::cout << "shear element (smoothed) after a cut: max |f_gl - f_ref| / max |f_ref| = " << error << "\n";
  EXPECT_LT(error, 1e-5);
}

// 1000 steps (100 ticks x 10) of the box released from a 2 % simple shear
// under gravity, so the element drives the motion: GL against a double
// reference within 1e-5 of the bounding-box diagonal, the tolerance and
// reasoning of parity_test.cpp (float positions random-walk ~1e-6 of the
// diagonal; a wrong or missing element moves points by millimetres). The
// reference: the reference backend (Verlet in double), for both forms.
TEST(GlShearElement, TrajectoryMatchesTheCpuReference) {
  for (const ShearFormulation formulation : kFormulations) {
    const Model model = gl_test::poisson_box(0.05, Vec3(0, 0, -9.81), Material{}.spring_damping_time, formulation);
    std::vector<Vec3> sheared = model.rest_position;
    for (int32_t i = 0; i < model.npoint(); ++i)
      if (!model.fixed[i]) sheared[i].x() += 0.02 * sheared[i].z();
    sheared = gl_test::round_to_float(sheared);
    const gl_test::TrajectoryDifference d = gl_test::cpu_and_gl_from(model, sheared, kDt, 100);
    const double diagonal = gl_test::bbox_diagonal(model);
    std::cout << "shear element (" << shear_formulation_name(formulation)
              << ") trajectory: max |x_gl - x_ref| / diagonal = " << d.worst / diagonal << ", motion " << d.motion << " m\n";
    ASSERT_GT(d.motion, 1e-4);  // it moved: a missing term would show
    EXPECT_LT(d.worst, 1e-5 * diagonal) << shear_formulation_name(formulation);
  }
}

}  // namespace
}  // namespace shear_element_test
}  // namespace organsim
