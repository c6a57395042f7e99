// Backend::rebuild on the GL backend: buffers re-uploaded from the new Model
// version with the state carried over on the GPU, checked
// against itself without a rebuild and against the double CPU reference
// after a cut made by hand (the topology code has its own tests).
#include <gtest/gtest.h>

#include <EGL/egl.h>

#include <future>

#include "core/gl/gl_backend.h"
#include "core/model/model_rebuild.h"
#include "core/sim/reference_backend.h"
#include "core/util/error.h"
#include "gl_test_scenes.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace rebuild_test {
namespace {

constexpr double kDt = 1e-4;
constexpr int kSubsteps = 10;

// A tick with the tool held at `at` (tool_to moved by the caller for a path).
TickRequest tool_held_at(const Vec3& at) {
  TickRequest r;
  r.dt = kDt;
  r.substeps = kSubsteps;
  r.tool_active = true;
  r.tool_from = r.tool_to = at;
  return r;
}

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
  auto cpu = make_reference_backend(model, {}, Integrator::Verlet);
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

// A sphere with the sub-cell Hertz layer pressing where a cut opens new
// faces: the layer's triangle table is repacked by prepare() with the
// surface and adopted at the tick, and the GL press follows the double CPU
// reference before and after (positions within 1e-5 of the diagonal, as
// the parity tests; the reaction within 3e-4 of its peak: a penalty 500 N/m
// stiff sinks 6 mm into a layer this soft, and each factor is the small
// difference m - k c delta of the two, so float's rounding of delta comes
// back 10-100 times larger; measured up to 1.4e-4 here. An adopt without
// the layer's table is off by more than the whole force).
TEST(GlRebuild, TheHertzLayerFollowsTheCpuReferenceAcrossACut) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  BackendTool tool{true, ToolMode::Push, 0.01, 500};
  tool.hertz_layer = true;
  auto cpu = make_reference_backend(model, tool, Integrator::Verlet);
  GlBackend gl(model, tool, {});
  TickRequest r = tool_held_at(Vec3(0.05, 0.05, 0.058));
  std::vector<Vec3> cpu_force, gl_force;
  const auto press = [&](int ticks) {
    for (int i = 0; i < ticks; ++i) {
      cpu_force.push_back(cpu->tick(r).force);
      gl_force.push_back(gl.tick(r).force);  // tick n's reaction arrives with tick n + 1
      r.tool_from = r.tool_to;
      r.tool_to -= Vec3(0, 0, 5e-5);
    }
  };
  press(20);
  cpu->rebuild(cut);
  gl.adopt(gl.prepare(cut));
  press(20);
  double worst = 0, peak = 0;
  for (size_t i = 0; i + 1 < gl_force.size(); ++i) {
    worst = std::max(worst, (gl_force[i + 1] - cpu_force[i]).norm());
    peak = std::max(peak, cpu_force[i].norm());
  }
  std::vector<Vec3> xc, xg;
  cpu->positions(xc);
  gl.positions(xg);
  ASSERT_EQ(xg.size(), xc.size());
  double moved = 0;
  for (size_t i = 0; i < xc.size(); ++i) moved = std::max(moved, (xg[i] - xc[i]).norm());
  EXPECT_GT(peak, 0.01) << "the sphere pressed";
  EXPECT_LT(worst, 3e-4 * peak);
  EXPECT_LT(moved / gl_test::bbox_diagonal(model), 1e-5);
}

// The rebuild split as the run loop does it for a change its worker builds:
// gl::pack_model on another thread while the backend ticks (prepare), the
// state read back and the buffers uploaded at the tick (adopt). With a
// pushing tool on the surface, so that the surface tables are repacked too.
TEST(GlRebuild, TablesPreparedWhileTickingAdoptExactlyAsARebuildAtTheTick) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  ASSERT_GT(cut.npoint(), model.npoint());
  const BackendTool tool{true, ToolMode::Push, 0.02, 500};
  std::vector<Vec3> x[2];
  std::vector<Reaction> reactions[2];
  for (int early = 0; early < 2; ++early) {
    GlBackend gl(model, tool, {});
    std::future<std::unique_ptr<PreparedModel>> prepared;
    if (early) prepared = std::async(std::launch::async, [&] { return gl.prepare(cut); });
    TickRequest r = tool_held_at(Vec3(0.05, 0.05, 0.065));
    for (int i = 0; i < 20; ++i) reactions[early].push_back(gl.tick(r));
    if (early) {
      gl.adopt(prepared.get());
    } else {
      gl.rebuild(cut);
    }
    r.tool_to = Vec3(0.05, 0.05, 0.04);
    for (int i = 0; i < 20; ++i) reactions[early].push_back(gl.tick(r));
    gl.positions(x[early]);
  }
  // The same buffers and dispatches: nothing may differ in any bit.
  ASSERT_EQ(x[0].size(), static_cast<size_t>(cut.npoint()));
  EXPECT_EQ(x[1], x[0]);
  double pushed = 0;
  for (size_t i = 0; i < reactions[0].size(); ++i) {
    EXPECT_EQ(reactions[1][i].force, reactions[0][i].force) << "tick " << i;
    pushed = std::max(pushed, reactions[0][i].force.norm());
  }
  EXPECT_GT(pushed, 0) << "the tool touched the box";
}

// prepare() uploads the tables on a context of its own that shares the
// backend's objects, so that adopt() on the tick only carries the state over:
// it leaves the calling thread's context as it found it (the backend's on
// the run loop, none on a worker), a version dropped without adopt() costs
// the backend nothing, and an adopted one has the buffers of a backend made
// from it.
TEST(GlRebuild, PrepareUploadsOnItsOwnContextAndRestoresTheCallers) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  const BackendTool tool{true, ToolMode::Push, 0.02, 500};
  GlBackend gl(model, tool, {});
  run(gl, 3);
  const void* loop_context = eglGetCurrentContext();
  ASSERT_EQ(loop_context, gl.context().egl_context());
  auto dropped = gl.prepare(cut);
  EXPECT_EQ(eglGetCurrentContext(), loop_context);
  dropped.reset();
  run(gl, 3);  // the dropped tables are deleted here, on the backend's context
  const void* worker_after = reinterpret_cast<void*>(1);
  auto prepared = std::async(std::launch::async, [&] {
                    auto p = gl.prepare(cut);
                    worker_after = eglGetCurrentContext();
                    return p;
                  }).get();
  EXPECT_EQ(worker_after, nullptr);  // EGL_NO_CONTEXT: nothing left current on a thread that ends
  gl.adopt(std::move(prepared));
  run(gl, 3);
  GlBackend fresh(cut, tool, {});
  const auto a = gl.plan().buffers, b = fresh.plan().buffers;
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].bytes, b[i].bytes) << a[i].name;
  }
}

// adopt() carries the state over on the GPU (carry_state.comp): no read of
// the state back to the CPU, and right after it the old points are where
// they were and every point the cut added is exactly at the old point it
// copies (Model::origin, followed back to a point the old version had).
TEST(GlRebuild, AnAdoptCarriesTheStateOverOnTheGpuWithoutReadingItBack) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  ASSERT_GT(cut.npoint(), model.npoint());
  GlBackend gl(model, {}, {});
  run(gl, 10);
  std::vector<Vec3> before, after;
  gl.positions(before);
  const int64_t readbacks = gl.state_readbacks();
  gl.adopt(gl.prepare(cut));
  EXPECT_EQ(gl.state_readbacks(), readbacks);
  gl.positions(after);
  ASSERT_EQ(after.size(), static_cast<size_t>(cut.npoint()));
  for (int32_t p = 0; p < cut.npoint(); ++p) {
    int32_t from = p;
    while (from >= model.npoint()) from = cut.origin[static_cast<size_t>(from)];
    ASSERT_EQ(after[p], before[from]) << "point " << p;
  }
  // And it goes on as a backend made from the cut in that state would: the
  // carried increments too (a copy that lost them would jump).
  run(gl, 5);
  gl.positions(after);
  for (const Vec3& x : after) EXPECT_TRUE(x.allFinite());
}

// Friction anchors are per point id, which a rebuild keeps, and adopt()
// copies them over on the GPU with the state: a sphere pressed into the
// box and dragged sideways, sticking, goes on through an identity rebuild
// mid-drag bit for bit as without it (anchors lost would let go and
// re-anchor where the points are then).
TEST(GlRebuild, AGripByFrictionHoldsThroughAnAdopt) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model same = rebuild_model(model, {model.tet_points, {}});
  BackendTool tool{true, ToolMode::Push, 0.02, 500, ToolContact::Surface};
  tool.friction = {2, 2};
  auto request = [](int n) {
    TickRequest r;
    r.dt = kDt;
    r.substeps = kSubsteps;
    r.tool_active = true;
    auto at = [](int k) { return Vec3(0.05 + 2e-4 * std::max(0, k - 10), 0.05, 0.066 - 4e-4 * std::min(k, 10)); };
    r.tool_from = at(n), r.tool_to = at(n + 1);
    return r;
  };
  std::vector<Vec3> x[2];
  double sideways = 0;
  for (int rebuilt = 0; rebuilt < 2; ++rebuilt) {
    GlBackend gl(model, tool, {});
    for (int n = 0; n < 30; ++n) {
      if (rebuilt && n == 20) gl.adopt(gl.prepare(same));
      const Reaction r = gl.tick(request(n));
      if (n == 29) sideways = std::abs(r.force.x());
    }
    gl.positions(x[rebuilt]);
  }
  EXPECT_GT(sideways, 0.01) << "the drag is held by friction";
  EXPECT_EQ(x[1], x[0]);
}

// keep_reaction_positions: after each tick, reaction_positions() are the
// positions at the end of the tick whose reaction it returned (the one
// before), bit for bit as positions() read them then, without waiting for
// the tick in flight; across an adopt() too (the copies' positions are their
// origins'). Without the option it refuses rather than read back the wrong tick.
TEST(GlRebuild, ReactionPositionsAreThoseOfTheReactionsTickAcrossAnAdopt) {
  const Model model = gl_test::box_model(4, 4, 2, true, 20000, Vec3(0, 0, -9.81));
  const Model cut = rebuild_model(model, testing::split_across_plane_x(model, 0.05));
  const BackendTool tool{true, ToolMode::Push, 0.02, 500};
  GlBackendOptions keep;
  keep.keep_reaction_positions = true;
  GlBackend gl(model, tool, keep);
  TickRequest r = tool_held_at(Vec3(0.05, 0.05, 0.045));
  std::vector<Vec3> before, kept;
  gl.tick(r);
  for (int i = 1; i < 12; ++i) {
    gl.positions(before);  // the end of tick i - 1
    if (i == 6) gl.adopt(gl.prepare(cut));
    ASSERT_GT(gl.tick(r).contacts, 0) << "tick " << i;
    gl.reaction_positions(kept);
    if (i == 6) {
      // The state carried over: the old points as they were, each copy at its origin.
      ASSERT_EQ(kept.size(), static_cast<size_t>(cut.npoint()));
      for (int32_t p = 0; p < cut.npoint(); ++p)
        ASSERT_EQ(kept[p], before[p < model.npoint() ? p : cut.origin[p]]) << "point " << p;
    } else {
      ASSERT_EQ(kept, before) << "tick " << i;
    }
  }
  std::vector<Vec3> now;
  gl.positions(now);
  EXPECT_NE(kept, now);  // the box sags and the tool presses: the tick in flight differs

  GlBackend plain(model, tool, {});
  plain.tick(r);
  plain.tick(r);
  EXPECT_THROW(plain.reaction_positions(kept), Error);
}

}  // namespace
}  // namespace rebuild_test
}  // namespace organsim
