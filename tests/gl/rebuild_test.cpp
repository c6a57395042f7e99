// Backend::rebuild on the GL backend: buffers re-uploaded from the new Model
// version with the state carried over (read back once per change), checked
// against itself without a rebuild and against the double CPU reference
// after a cut made by hand (the topology code has its own tests).
#include <gtest/gtest.h>

#include "core/gl/gl_backend.h"
#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "gl_test_scenes.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace {

constexpr double kDt = 1e-4;
constexpr int kSubsteps = 10;

void run(Backend& backend, int ticks) {
  TickRequest r;
  r.dt = kDt;
  r.substeps = kSubsteps;
  for (int i = 0; i < ticks; ++i) backend.tick(r);
}

TEST(GlRebuild, IdentityRebuildKeepsTheTrajectory) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model same = rebuild_model(model, {model.tet_points, {}});
  Model frozen = same;  // the same topology with every point fixed (1/m = 0)
  std::fill(frozen.fixed.begin(), frozen.fixed.end(), 1);
  std::fill(frozen.inv_mass.begin(), frozen.inv_mass.end(), 0.0);
  GlBackend straight(model, {}, {}), rebuilt(model, {}, {});
  run(straight, 20);
  run(rebuilt, 10);
  rebuilt.rebuild(same);
  run(rebuilt, 10);
  std::vector<Vec3> a, b;
  straight.positions(a);
  rebuilt.positions(b);
  ASSERT_EQ(a.size(), b.size());
  // The same float buffers and the same dispatches: the state read back and
  // re-uploaded is exact, so nothing may differ.
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << "point " << i;
  // A rebuild that did nothing would pass that too: rebuilt into `frozen`,
  // no point may move any more.
  rebuilt.rebuild(frozen);
  run(rebuilt, 5);
  std::vector<Vec3> c;
  rebuilt.positions(c);
  EXPECT_EQ(c, b);
}

// Hanging under gravity, fixed at its base, cut through the middle at 20 ms:
// the GL backend follows the double CPU reference through the rebuild.
// Tolerance as tests/gl/parity_test.cpp: 1e-5 of the box diagonal (float
// rounding random-walks to ~1e-6 over these 400 steps; a copy that lost its
// velocity or a wrongly re-uploaded buffer moves points by millimetres).
TEST(GlRebuild, MatchesTheCpuReferenceAcrossACut) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  ASSERT_GT(cut.npoint(), model.npoint());
  auto cpu = make_cpu_backend(model, {}, {Precision::Double, 1});
  GlBackend gl(model, {}, {});
  run(*cpu, 20);
  run(gl, 20);
  cpu->rebuild(cut);
  gl.rebuild(cut);
  run(*cpu, 20);
  run(gl, 20);
  std::vector<Vec3> xc, xg;
  cpu->positions(xc);
  gl.positions(xg);
  ASSERT_EQ(xc.size(), static_cast<size_t>(cut.npoint()));
  ASSERT_EQ(xg.size(), xc.size());
  const double diagonal = gl_test::bbox_diagonal(model);
  double worst = 0, moved = 0;
  for (size_t i = 0; i < xc.size(); ++i) {
    worst = std::max(worst, (xg[i] - xc[i]).norm() / diagonal);
    moved = std::max(moved, (xc[i] - cut.rest_position[i]).norm());
  }
  EXPECT_LT(worst, 1e-5);
  EXPECT_GT(moved, 1e-5);  // it sagged, so the comparison means something
}

}  // namespace
}  // namespace organsim
