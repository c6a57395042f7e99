// The run loop's topology events on the GL backend (issue 8): a blade cuts
// a block held at its base while a sphere presses next to the cut; the GL
// run follows the double CPU reference through every change.
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/run/run.h"
#include "gl_test_scenes.h"

namespace organsim {
namespace topology_parity_test {
namespace {

// A 4 cm block (4 x 4 x 4 cubes) held at its base under gravity. From 10 to
// 30 ms a blade in the grid plane x = 2 cm cuts down from the top to
// z = 1 cm; a 1 cm sphere presses into the top at x = 3 cm from 0 to 60 ms.
Scenario cut_block() {
  Scenario s;
  s.file = "cut_block.json";
  s.material.density = 1000;
  s.material.young_modulus = 5000;
  s.material.spring_damping_time = 1e-3;
  s.material.volume_modulus = 10000;
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-6);
  base.normal = Vec3(0, 0, -1);
  s.fixed = {base};
  s.time.duration = 0.06;
  s.time.dt = 1e-4;
  s.time.substeps = 10;
  ToolDef tool;
  tool.spec.radius = 0.01;
  tool.spec.contact_stiffness = 200;
  tool.spec.keyframes = {{0.0, Vec3(0.03, 0.02, 0.05)}, {0.06, Vec3(0.03, 0.02, 0.042)}};
  s.tool = tool;
  CutEvent cut;
  cut.name = "incision";
  cut.keyframes = {{0.010, Vec3(0.02, -0.01, 0.05), Vec3(0.02, 0.05, 0.05)},
                   {0.030, Vec3(0.02, -0.01, 0.01), Vec3(0.02, 0.05, 0.01)}};
  s.events.cuts = {cut};
  return s;
}

// Tolerances as tests/gl/parity_test.cpp: positions 1e-5 of the box
// diagonal, tool force 1e-4 of the peak reaction (float rounding); a copy
// that lost its state or a stale buffer after a rebuild is off by far more.
// With one invocation per point (llvmpipe's default) and with 8 (a GPU's):
// the rebuilt gathers are split over the invocations too.
TEST(GlTopology, CutRunMatchesTheCpuReference) {
  const Scenario s = cut_block();
  const Model model = build_model(make_box_tet_mesh(Vec3::Zero(), Vec3::Constant(0.04), 4, 4, 4), s.material,
                                  model_options(s), "block");
  for (const int32_t threads_per_point : {1, 8}) {
    SCOPED_TRACE(std::to_string(threads_per_point) + " invocation(s) per point");
    const gl_test::CpuAndGlRuns r = gl_test::run_on_cpu_and_gl(
        s, model, "gl_topology_" + std::to_string(threads_per_point), threads_per_point);
    ASSERT_GT(r.cpu_end.changes, 1);
    EXPECT_EQ(r.gl_end.changes, r.cpu_end.changes);  // the same faces cut at the same ticks
    ASSERT_EQ(r.gl_end.x.size(), r.cpu_end.x.size());
    EXPECT_LT(r.worst_position_difference(gl_test::bbox_diagonal(model)), 1e-5);
    // The GL reaction arrives one tick late (non-blocking readback).
    const size_t lag = static_cast<size_t>(r.gl_latency);
    double peak = 0, force_error = 0;
    for (size_t i = 0; i + lag < r.cpu.samples.size(); ++i) {
      peak = std::max(peak, r.cpu.samples.force[i].norm());
      force_error = std::max(force_error, (r.gl.samples.force[i + lag] - r.cpu.samples.force[i]).norm());
    }
    ASSERT_GT(peak, 0);  // the tool touched
    EXPECT_LT(force_error, 1e-4 * peak);
  }
}

}  // namespace
}  // namespace topology_parity_test
}  // namespace organsim
