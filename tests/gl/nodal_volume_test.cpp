// The GL backend with the averaged nodal volume term (nodal_pressure.comp,
// then step.comp's NODAL_VOLUME variant) against the double CPU reference:
// the force of one step on a deformed box, and 1000 steps of a sagging box.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace {

constexpr double kDt = 1e-4;  // s

// The shared soft box (E 3 kPa) with nu = 0.45 and its nodal volume term.
Model nodal_box(const Vec3& gravity) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), 5, 5, 3);
  Material material;
  material.young_modulus = 3000;
  material.poisson_ratio = 0.45;
  ModelOptions options;
  options.gravity = gravity;
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Plane;
  bottom.point = Vec3(0, 0, 1e-9);
  bottom.normal = Vec3(0, 0, -1);
  options.fixed.push_back(bottom);
  return build_model(mesh, material, options, "test box");
}

// With 1, 3 and 8 invocations per point (step.comp and nodal_pressure.comp
// share THREADS_PER_POINT; kernel_test.cpp says why those three).
TEST(GlNodalVolume, ForceMatchesTheReference) {
  const Model model = nodal_box(Vec3(0, 0, -9.81));
  ASSERT_TRUE(model.has_nodal_volume());
  for (const int32_t threads_per_point : {1, 3, 8}) {
    SCOPED_TRACE("threads per point " + std::to_string(threads_per_point));
    GlBackendOptions options;
    options.record_forces = true;
    options.threads_per_point = threads_per_point;
    GlBackend gl(model, BackendTool{}, options);
    EXPECT_EQ(gl.plan().dispatches_per_step, 2);
    const gl_test::MovingState s = gl_test::moving_state(model, kDt);
    const std::vector<Vec3> got = gl_test::forces_of_one_substep(gl, s, kDt);
    std::vector<Vec3> want;
    reference_internal_forces(model, s.x, s.v, want);
    double worst = 0, largest = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      worst = std::max(worst, (got[i] - want[i]).norm());
      largest = std::max(largest, want[i].norm());
    }
    std::cout << "nodal, " << threads_per_point << " invocation(s) per point: max |f_gl - f_ref| / max |f_ref| = "
              << worst / largest << "\n";
    // Float: a nodal volume change (~5 % of V_a here) is the difference of two
    // sums of ~24 tet volumes each rounded at ~1e-7 relative, so its pressure
    // carries ~1e-6 relative error, and the springs as in kernel_test.cpp; a
    // wrong index, sign or factor gives errors of order 1. Tolerance 1e-5.
    EXPECT_LT(worst, 1e-5 * largest);
  }
}

// 1000 steps (100 ticks x 10) of the box released from a 2 % uniform
// squeeze under gravity, so the nodal pressures drive the motion: GL against
// the CPU double reference within 1e-5 of the bounding-box diagonal, the
// tolerance and reasoning of parity_test.cpp (float positions random-walk
// ~1e-6 of the diagonal; a wrong or missing pressure pass moves points by
// millimetres).
TEST(GlNodalVolume, TrajectoryMatchesTheCpuReference) {
  const Model model = nodal_box(Vec3(0, 0, -9.81));
  std::vector<Vec3> squeezed = model.rest_position;
  const Vec3 centre(0.05, 0.05, 0.0);
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) squeezed[i] = centre + 0.98 * (squeezed[i] - centre);
  squeezed = gl_test::round_to_float(squeezed);
  auto cpu = make_cpu_backend(model, {}, {Precision::Double, 1});
  GlBackend gl(model, BackendTool{}, {});
  cpu->set_state(squeezed, squeezed);
  gl.set_state(squeezed, squeezed);
  TickRequest request;
  request.dt = kDt;
  request.substeps = 10;
  // Compared after every tick: the squeeze springs back within the first
  // ~10 ms (the dampers then settle it), so the pressures matter early.
  double worst = 0, motion = 0;
  std::vector<Vec3> xc, xg;
  for (int n = 0; n < 100; ++n) {
    cpu->tick(request);
    gl.tick(request);
    cpu->positions(xc);
    gl.positions(xg);
    for (int32_t i = 0; i < model.npoint(); ++i) {
      worst = std::max(worst, (xg[i] - xc[i]).norm());
      motion = std::max(motion, (xc[i] - squeezed[i]).norm());
    }
  }
  const double diagonal = gl_test::bbox_diagonal(model);
  std::cout << "nodal trajectory: max |x_gl - x_cpu| / diagonal = " << worst / diagonal << ", motion " << motion
            << " m\n";
  ASSERT_GT(motion, 1e-4);  // it moved: a missing term would show
  EXPECT_LT(worst, 1e-5 * diagonal);
}

}  // namespace
}  // namespace organsim
