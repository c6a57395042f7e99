// Sutures on the GL backend (issue 8): step.comp's tension-only springs with
// rest lengths refreshed from their schedule match the double reference, and
// a run that cuts and then sutures follows the double CPU backend.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/gl/gl_backend.h"
#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/reference_forces.h"
#include "gl_test_scenes.h"
#include "tests/core/suture_test_util.h"

namespace organsim {
namespace {

namespace fs = std::filesystem;

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
  const std::vector<Vec3> x = gl_test::perturbed(model, 1e-3, 5);
  std::vector<Vec3> x_prev = x, v(x.size());
  std::uniform_real_distribution<double> u(-1e-6, 1e-6);
  for (Vec3& p : x_prev) p += Vec3(u(rng), u(rng), u(rng));
  x_prev = gl_test::round_to_float(x_prev);
  const double dt = 1e-4;
  for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev[i]) / dt;
  gl.set_state(x, x_prev);
  TickRequest request;
  request.dt = dt;
  request.substeps = 1;
  gl.tick(request);
  std::vector<Vec3> got, want, when_tied;
  gl.forces(got);
  reference_internal_forces(model, x, v, want, 0.0);
  reference_internal_forces(model, x, v, when_tied, -0.1);
  double err = 0, scale = 0, schedule = 0;
  for (size_t i = 0; i < want.size(); ++i) {
    err = std::max(err, (got[i] - want[i]).norm());
    scale = std::max(scale, want[i].norm());
    schedule = std::max(schedule, (when_tied[i] - want[i]).norm());
  }
  EXPECT_LT(err, 1e-5 * scale);
  EXPECT_GT(schedule, 0.1 * scale);  // the schedule changes the forces: the test can tell
}

// The beam of tests/core/suture_test_util.h, cut at 0-10 ms and sutured at
// 50 ms, to 150 ms: the GL run makes the same changes and ends where the
// double CPU run does. Tolerance 1e-5 of the beam's diagonal as
// tests/gl/topology_parity_test.cpp (float rounding over 1500 steps).
TEST(GlSuture, CutThenSutureRunMatchesTheCpuReference) {
  const Scenario s = testing::sutured_beam(0.05, 0.15);
  const Model model = testing::beam_model(s);
  auto cpu = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  GlBackend gl(model, backend_tool(s), {});
  gl_test::FinalState cpu_end, gl_end;
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "gl_suture_cpu";
  options.observers = {&cpu_end};
  const RunResult rc = run_scenario(s, model, *cpu, options);
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "gl_suture_gl";
  options.observers = {&gl_end};
  const RunResult rg = run_scenario(s, model, gl, options);
  ASSERT_GT(cpu_end.changes, 1);
  EXPECT_EQ(gl_end.changes, cpu_end.changes);
  EXPECT_EQ(rg.meta.extra["sutures"]["count"], rc.meta.extra["sutures"]["count"]);
  ASSERT_GT(rc.meta.extra["sutures"]["count"].get<int>(), 0);
  ASSERT_EQ(gl_end.x.size(), cpu_end.x.size());
  const double diagonal = gl_test::bbox_diagonal(model);
  double worst = 0;
  for (size_t i = 0; i < cpu_end.x.size(); ++i) worst = std::max(worst, (gl_end.x[i] - cpu_end.x[i]).norm() / diagonal);
  std::cout << "GL vs CPU after cut and sutures: " << worst << " of the diagonal\n";
  EXPECT_LT(worst, 1e-5);
}

}  // namespace
}  // namespace organsim
