// The GL backend with the averaged nodal volume term (nodal_pressure.comp,
// then step.comp's NODAL_VOLUME variant) against the double CPU reference:
// the force of one step on a deformed box, and 1000 steps of a sagging box.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace nodal_volume_test {
namespace {

constexpr double kDt = 1e-4;  // s

// With 1, 3 and 8 invocations per point (step.comp and nodal_pressure.comp
// share THREADS_PER_POINT; kernel_test.cpp says why those three).
TEST(GlNodalVolume, ForceMatchesTheReference) {
  const Model model = gl_test::poisson_box(0.45, Vec3(0, 0, -9.81));
  ASSERT_TRUE(model.has_nodal_volume());
  for (const int32_t threads_per_point : {1, 3, 8}) {
    SCOPED_TRACE("threads per point " + std::to_string(threads_per_point));
    GlBackendOptions options;
    options.threads_per_point = threads_per_point;
    EXPECT_EQ(GlBackend(model, BackendTool{}, options).plan().dispatches_per_step, 2);
    const double error =
        gl_test::one_substep_force_error(model, gl_test::moving_state(model, kDt), kDt, threads_per_point);
    std::cout << "nodal, " << threads_per_point << " invocation(s) per point: max |f_gl - f_ref| / max |f_ref| = "
              << error << "\n";
    // Float: a nodal volume change (~5 % of V_a here) is the difference of two
    // sums of ~24 tet volumes each rounded at ~1e-7 relative, so its pressure
    // carries ~1e-6 relative error, and the springs as in kernel_test.cpp; a
    // wrong index, sign or factor gives errors of order 1. Tolerance 1e-5.
    EXPECT_LT(error, 1e-5);
  }
}

// 1000 steps (100 ticks x 10) of the box released from a 2 % uniform
// squeeze under gravity, so the nodal pressures drive the motion: GL against
// the CPU double reference within 1e-5 of the bounding-box diagonal, the
// tolerance and reasoning of parity_test.cpp (float positions random-walk
// ~1e-6 of the diagonal; a wrong or missing pressure pass moves points by
// millimetres).
TEST(GlNodalVolume, TrajectoryMatchesTheCpuReference) {
  const Model model = gl_test::poisson_box(0.45, Vec3(0, 0, -9.81));
  const std::vector<Vec3> squeezed = gl_test::squeezed_box(model);
  // Compared after every tick: the squeeze springs back within the first
  // ~10 ms (the dampers then settle it), so the pressures matter early.
  const gl_test::TrajectoryDifference d = gl_test::cpu_and_gl_from(model, squeezed, kDt, 100);
  const double diagonal = gl_test::bbox_diagonal(model);
  std::cout << "nodal trajectory: max |x_gl - x_cpu| / diagonal = " << d.worst / diagonal << ", motion " << d.motion
            << " m\n";
  ASSERT_GT(d.motion, 1e-4);  // it moved: a missing term would show
  EXPECT_LT(d.worst, 1e-5 * diagonal);
}

}  // namespace
}  // namespace nodal_volume_test
}  // namespace organsim
