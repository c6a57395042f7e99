// Sutures on the GL backend (issue 8): step.comp's tension-only springs with
// rest lengths refreshed from their schedule match the double reference, and
// a run that cuts and then sutures follows the double CPU backend.
#include <gtest/gtest.h>

#include <random>

#include "core/gl/gl_backend.h"
#include "core/model/model_rebuild.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"
#include "tests/core/suture_test_util.h"

namespace organsim {
namespace suture_test {
namespace {

// Tolerance as tests/gl/kernel_test.cpp: the kernel sees the reference's
// input (positions rounded to float), so only float arithmetic differs
// (measured a few 1e-7); 1e-5 of the largest force. A suture that pushed, or
// a rest length not refreshed from the schedule, is off by order 1 (the
// sutures here carry forces of the order of the largest).
TEST(GlSuture, TensionOnlySuturesOnTheirScheduleMatchTheReference) {
  const Model plain = gl_test::box_model(5, 5, 3, true, 2e4, Vec3(0, 0, -9.81));
  std::mt19937 rng(3);
  std::uniform_int_distribution<int32_t> pick(0, plain.npoint() - 1);
  std::vector<Suture> sutures;
  for (int k = 0; k < 16; ++k) {
    const int32_t a = pick(rng), b = pick(rng);
    if (a == b) continue;
    Suture u;
    u.ends = {std::min(a, b), std::max(a, b)};
    u.k = 100;
    u.length = (k % 2 ? 1.1 : 0.8) * (plain.rest_position[b] - plain.rest_position[a]).norm();
    u.tied_at = -0.1;  // 0.1 s of tightening at 5 cm/s before the first tick: 5 mm shorter
    u.rate = 0.05;
    sutures.push_back(u);
  }
  const Model model = add_sutures(plain, sutures);
  GlBackendOptions options;
  options.record_forces = true;
  GlBackend gl(model, BackendTool{}, options);
  const double dt = 1e-4;
  const gl_test::MovingState state = gl_test::moving_state(model, dt, 5);
  const std::vector<Vec3> got = gl_test::forces_of_one_substep(gl, state, dt);
  std::vector<Vec3> want, when_tied;
  reference_internal_forces(model, state.x, state.v, want, 0.0);
  reference_internal_forces(model, state.x, state.v, when_tied, -0.1);
  double err = 0, scale = 0, schedule = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    err = std::max(err, (got[i] - want[i]).norm());
    scale = std::max(scale, want[i].norm());
    schedule = std::max(schedule, (when_tied[i] - want[i]).norm());
  }
  EXPECT_LT(err, 1e-5 * scale);
  EXPECT_GT(schedule, 0.1 * scale);  // the schedule changes the forces: the test can tell
  // Both kinds are at this state, so a suture that pushed while slack, or
  // one that never pulled, would be seen: some are longer than their rest
  // length at t = 0 (they pull), some shorter (slack: no force).
  int taut = 0, slack = 0;
  for (int32_t s = model.first_suture(); s < model.nspring(); ++s) {
    const Edge& e = model.spring_ends[s];
    ((state.x[e[1]] - state.x[e[0]]).norm() > model.spring_rest_at(s, 0.0) ? taut : slack) += 1;
  }
  EXPECT_GT(taut, 0);
  EXPECT_GT(slack, 0);
}

// The beam of tests/core/suture_test_util.h, cut at 0-10 ms and sutured at
// 50 ms, to 150 ms: the GL run makes the same changes and ends where the
// double CPU run does. Tolerance 1e-5 of the beam's diagonal as
// tests/gl/topology_parity_test.cpp (float rounding over 1500 steps).
TEST(GlSuture, CutThenSutureRunMatchesTheCpuReference) {
  const Scenario s = testing::sutured_beam(0.05, 0.15);
  const Model model = testing::beam_model(s);
  const gl_test::CpuAndGlRuns r = gl_test::run_on_cpu_and_gl(s, model, "gl_suture");
  ASSERT_GT(r.cpu_end.changes, 1);
  EXPECT_EQ(r.gl_end.changes, r.cpu_end.changes);
  EXPECT_EQ(r.gl.meta.extra["sutures"]["count"], r.cpu.meta.extra["sutures"]["count"]);
  ASSERT_GT(r.cpu.meta.extra["sutures"]["count"].get<int>(), 0);
  ASSERT_EQ(r.gl_end.x.size(), r.cpu_end.x.size());
  const double worst = r.worst_position_difference(gl_test::bbox_diagonal(model));
  std::cout << "GL vs CPU after cut and sutures: " << worst << " of the diagonal\n";
  EXPECT_LT(worst, 1e-5);
}

}  // namespace
}  // namespace suture_test
}  // namespace organsim
