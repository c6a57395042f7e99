// The run loop on the CPU backend with small box meshes: timeline, tool
// contact, grasp/release, observers, and a valid log when a run is cut short.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/mesh/tet_mesh.h"
#include "core/sim/cpu_backend.h"
#include "core/run/run.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"

namespace organsim {
namespace run_loop_test {
namespace {

namespace fs = std::filesystem;

// A 0.1 m soft cube (E = 3 kPa, liver-like) fixed at its bottom face, no
// gravity so that any force on the tool comes from contact alone.
Scenario cube_scenario() {
  Scenario s;
  s.file = "cube.json";
  s.material.young_modulus = 3000;
  s.material.density = 1060;
  // Springs alone let a tet lattice fold under a local load; the volume term keeps it a solid.
  s.material.volume_modulus = 10000;
  s.gravity = Vec3::Zero();
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Box;
  bottom.min = Vec3(-1, -1, -1);
  bottom.max = Vec3(1, 1, 1e-6);
  s.fixed = {bottom};
  s.time.duration = 0.5;
  s.time.dt = 1e-4;
  s.time.substeps = 10;
  return s;
}

// Tool of radius 2.5 cm coming down at 4 cm/s on the middle of the top face
// (z = 0.1), right above a grid point: contact starts at t = 0.125 s (centre
// at z = 0.125) and the tool has travelled 1.5 cm past contact at t = 0.5 s.
void add_push_tool(Scenario& s) {
  ToolDef tool;
  tool.spec.radius = 0.025;
  tool.spec.contact_stiffness = 200;
  tool.spec.keyframes = {{0.0, Vec3(0.05, 0.05, 0.13)}, {0.5, Vec3(0.05, 0.05, 0.11)}};
  s.tool = tool;
}

Model cube_model(const Scenario& s) {
  // 8 x 8 x 8 cubes of 1.25 cm: a grid point sits at the top face's centre
  // (0.05, 0.05, 0.1), and the tool touches several points at once.
  return build_model(make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 8, 8, 8), s.material,
                     model_options(s), "cube");
}

// One thread: the test machine is shared, and OpenMP's spinning threads make
// small models slow under load. Thread counts do not change results (the
// reduction order is fixed), so nothing is lost.
CpuBackendOptions single_thread() {
  CpuBackendOptions o;
  o.threads = 1;
  return o;
}

fs::path outdir(const std::string& name) {
  const fs::path d = fs::path(ORGANSIM_TEST_TMP) / name;
  fs::remove_all(d);
  return d;
}

TEST(RunLoop, OneSamplePerTickFollowingTheKeyframes) {
  Scenario s = cube_scenario();
  add_push_tool(s);
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  RunOptions o;
  o.outdir = outdir("run_timeline");
  const RunResult r = run_scenario(s, model, *backend, o);

  ASSERT_EQ(r.samples.size(), 500u);  // 0.5 s at a 1 ms tick
  EXPECT_NEAR(r.samples.t.front(), 1e-3, 1e-15);
  EXPECT_NEAR(r.samples.t.back(), 0.5, 1e-12);
  // Linear keyframes: z(t) = 0.13 - 0.04 t, exact up to rounding.
  for (size_t i = 0; i < r.samples.size(); i += 50) {
    EXPECT_NEAR(r.samples.tool_position[i].z(), 0.13 - 0.04 * r.samples.t[i], 1e-12);
  }
  EXPECT_NEAR(backend->time(), 0.5, 1e-9);  // 5000 steps of 1e-4 s
  EXPECT_TRUE(r.meta.completed);
  EXPECT_GT(r.meta.steps_per_second, 0);
  // 0.5 s simulated over the loop's wall time.
  EXPECT_NEAR(r.meta.real_time_factor, 0.5 / r.meta.wall_seconds, 1e-9 * r.meta.real_time_factor);

  const auto j = nlohmann::json::parse(read_text_file(o.outdir / "forces.json"));
  EXPECT_EQ(j["samples"]["t"].size(), 500u);
  EXPECT_EQ(j["samples"]["force"].size(), 500u);
  EXPECT_EQ(j["meta"]["points"], model.npoint());
  EXPECT_EQ(j["meta"]["backend"], "cpu");
  EXPECT_EQ(j["meta"]["completed"], true);
}

TEST(RunLoop, PushGivesNoForceBeforeContactThenAnOpposingForceGrowingWithDepth) {
  Scenario s = cube_scenario();
  add_push_tool(s);
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  RunOptions o;
  o.outdir = outdir("run_push");
  const RunResult r = run_scenario(s, model, *backend, o);

  const Vec3 push_dir(0, 0, -1);
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const double t = r.samples.t[i];
    // Before t = 0.125 s the sphere's bottom is above the top face: exactly no force.
    if (t < 0.124) {
      EXPECT_EQ(r.samples.force[i].norm(), 0.0) << "t = " << t;
      EXPECT_EQ(r.samples.contacts[i], 0);
    }
  }
  // Once in contact, the reaction on the tool opposes the push (points up)
  // and grows with depth: 5, 10 and 15 mm of tool travel past contact.
  auto force_at = [&](double t) { return r.samples.force[static_cast<size_t>(std::lround(t / 1e-3)) - 1]; };
  const Vec3 f1 = force_at(0.25), f2 = force_at(0.375), f3 = force_at(0.5);
  for (const Vec3& f : {f1, f2, f3}) {
    EXPECT_LT(f.dot(push_dir), 0.0);
    // Mostly along the push axis: the contact is centred on the cube; the Kuhn
    // split is not mirror-symmetric, so allow 20 % lateral force.
    EXPECT_LT(std::hypot(f.x(), f.y()), 0.2 * std::abs(f.z()));
  }
  EXPECT_GT(f2.z(), f1.z() * 1.2);  // deeper => clearly larger (20 % margin over noise)
  EXPECT_GT(f3.z(), f2.z() * 1.2);
  EXPECT_GT(r.samples.contacts.back(), 0);
}

// A grasper sitting on the top face's centre closes at 0.05 s, lifts 2 cm
// by 0.25 s (the keyframes hold before the first) and lets go at 0.3 s.
void add_pull_tool(Scenario& s) {
  ToolDef tool;
  tool.spec.mode = ToolMode::Pull;
  tool.spec.radius = 0.01;
  tool.spec.grasp_radius = 0.025;
  tool.spec.contact_stiffness = 200;
  tool.spec.grasp_time = 0.05;
  tool.spec.release_time = 0.3;
  tool.spec.keyframes = {{0.05, Vec3(0.05, 0.05, 0.1)}, {0.25, Vec3(0.05, 0.05, 0.12)}};
  s.tool = tool;
}

TEST(RunLoop, PullGraspsNearbyPointsDragsThemAndReleases) {
  Scenario s = cube_scenario();
  add_pull_tool(s);
  s.time.duration = 0.4;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  RunOptions o;
  o.outdir = outdir("run_pull");
  const RunResult r = run_scenario(s, model, *backend, o);

  // Top-face points within 2.5 cm of the centre on a 2 cm grid: 5 at least.
  EXPECT_GE(r.grasped_points, 5);
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const double t = r.samples.t[i];
    if (t <= 0.05 + 1e-9) {
      EXPECT_EQ(r.samples.contacts[i], 0) << "before the grasp, t = " << t;
    }
    if (t > 0.301) {
      EXPECT_EQ(r.samples.force[i].norm(), 0.0) << "after the release, t = " << t;
    }
  }
  // While lifting, the tissue pulls the tool back down.
  const size_t lift = static_cast<size_t>(std::lround(0.25 / 1e-3)) - 1;
  EXPECT_EQ(r.samples.contacts[lift], r.grasped_points);
  EXPECT_LT(r.samples.force[lift].z(), 0.0);
}

// Copies the positions at the chosen ticks.
class PositionProbe : public RunObserver {
 public:
  explicit PositionProbe(std::vector<int64_t> ticks) : ticks_(std::move(ticks)), positions(ticks_.size()) {}
  void on_tick(const Model&, Backend& backend, const TickInfo& info) override {
    for (size_t k = 0; k < ticks_.size(); ++k) {
      if (info.tick == ticks_[k]) backend.positions(positions[k]);
    }
  }
  std::vector<int64_t> ticks_;
  std::vector<std::vector<Vec3>> positions;
};

TEST(RunLoop, GraspedPointsMoveWithTheToolAndFixedPointsStay) {
  Scenario s = cube_scenario();
  add_pull_tool(s);
  s.time.duration = 0.3;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  PositionProbe probe({49, 249, 299});  // the grasp tick, the end of the lift, the release
  RunOptions o;
  o.outdir = outdir("run_pull_moves");
  o.observers = {&probe};
  const RunResult r = run_scenario(s, model, *backend, o);
  ASSERT_GE(r.grasped_points, 5);

  // The grasped set, as the run loop chose it at the grasp tick.
  const Attachment grasped = select_grasp(model, probe.positions[0], Vec3(0.05, 0.05, 0.1), 0.025);
  ASSERT_EQ(static_cast<int32_t>(grasped.points.size()), r.grasped_points);
  // Mean z displacement of the grasped points since the grasp.
  const auto rise = [&](const std::vector<Vec3>& x) {
    double sum = 0;
    for (int32_t i : grasped.points) sum += x[i].z() - probe.positions[0][i].z();
    return sum / static_cast<double>(grasped.points.size());
  };
  // The tool rose 2 cm; its 200 N/m springs against the soft cube's pull
  // leave the points some way behind, but they follow: more than a quarter
  // of the lift, never more than the lift itself, and still up while held.
  EXPECT_GT(rise(probe.positions[1]), 0.005) << "grasped points did not follow the tool";
  EXPECT_LT(rise(probe.positions[1]), 0.02 + 1e-3);
  EXPECT_GT(rise(probe.positions[2]), 0.005);
  // Fixed points (the bottom face) never move.
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if (model.fixed[i]) {
      EXPECT_EQ(probe.positions[2][i], model.rest_position[i]) << "fixed point " << i << " moved";
    }
  }
}

TEST(RunLoop, KeyframesHoldBeforeTheFirstAndAfterTheLast) {
  Scenario s = cube_scenario();
  add_push_tool(s);
  // Far above the cube (no contact): the path is all that matters here.
  s.tool->spec.keyframes = {{0.1, Vec3(0.05, 0.05, 0.5)}, {0.2, Vec3(0.15, 0.05, 0.6)}};
  s.time.duration = 0.3;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  RunOptions o;
  o.outdir = outdir("run_keyframes_outside");
  const RunResult r = run_scenario(s, model, *backend, o);
  ASSERT_EQ(r.samples.size(), 300u);
  for (size_t i = 0; i < r.samples.size(); ++i) {
    const double t = r.samples.t[i];
    const Vec3& p = r.samples.tool_position[i];
    if (t <= 0.1) {
      EXPECT_EQ(p, Vec3(0.05, 0.05, 0.5)) << "before the first keyframe, t = " << t;
    } else if (t >= 0.2) {
      EXPECT_EQ(p, Vec3(0.15, 0.05, 0.6)) << "after the last keyframe, t = " << t;
    } else {
      // Linear in between, exact up to rounding of t.
      const double u = (t - 0.1) / 0.1;
      EXPECT_NEAR((p - Vec3(0.05 + 0.1 * u, 0.05, 0.5 + 0.1 * u)).norm(), 0.0, 1e-12) << "t = " << t;
    }
  }
  // One keyframe: the tool stays there for the whole run.
  s.tool->spec.keyframes = {{0.15, Vec3(0.01, 0.02, 0.7)}};
  auto one = make_cpu_backend(model, backend_tool(s), single_thread());
  const RunResult still = run_scenario(s, model, *one, o);
  for (const Vec3& p : still.samples.tool_position) EXPECT_EQ(p, Vec3(0.01, 0.02, 0.7));
}

TEST(RunLoop, GraspSelectsFreePointsWithinTheRadiusWithTheirOffsets) {
  const Scenario s = cube_scenario();  // bottom face (z = 0) fixed
  const Model model = cube_model(s);
  std::vector<Vec3> x = model.rest_position;
  // A 2 cm ball about the centre of the bottom face: its free points are the
  // ones above z = 0, counted here by brute force in input numbering.
  const Vec3 center(0.05, 0.05, 0.0);
  const Attachment a = select_grasp(model, x, center, 0.02);
  int expected = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    if ((x[i] - center).norm() <= 0.02 && x[i].z() > 1e-9) ++expected;
  }
  ASSERT_GT(expected, 0);
  EXPECT_EQ(static_cast<int>(a.points.size()), expected);
  for (size_t k = 0; k < a.points.size(); ++k) {
    EXPECT_FALSE(model.fixed[a.points[k]]) << "a fixed point cannot be grasped";
    EXPECT_NEAR((a.offsets[k] - (x[a.points[k]] - center)).norm(), 0.0, 1e-15);
  }
}

// Counts the calls it gets; optionally throws at one tick.
class CountingObserver : public RunObserver {
 public:
  explicit CountingObserver(int64_t throw_at = -1) : throw_at_(throw_at) {}
  void on_start(const Model&, Backend&) override { ++starts; }
  void on_tick(const Model&, Backend&, const TickInfo& info) override {
    ++ticks;
    last_t = info.t;
    if (info.tick == throw_at_) throw Error(ErrorKind::Numerical, "observer stop at tick " + std::to_string(info.tick));
  }
  void on_finish(const Model&, Backend&) override { ++finishes; }
  int starts = 0, ticks = 0, finishes = 0;
  double last_t = 0;

 private:
  int64_t throw_at_;
};

TEST(RunLoop, ObserversSeeEveryTickAndAreFinishedOnce) {
  Scenario s = cube_scenario();
  s.time.duration = 0.05;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  CountingObserver a, b;
  RunOptions o;
  o.outdir = outdir("run_observers");
  o.observers = {&a, &b};
  run_scenario(s, model, *backend, o);
  for (const CountingObserver* c : {&a, &b}) {
    EXPECT_EQ(c->starts, 1);
    EXPECT_EQ(c->ticks, 50);
    EXPECT_EQ(c->finishes, 1);
    EXPECT_NEAR(c->last_t, 0.05, 1e-12);
  }
}

TEST(RunLoop, ARunCutShortStillWritesAValidLogThatSaysWhy) {
  Scenario s = cube_scenario();
  s.time.duration = 0.05;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  CountingObserver stopper(/*throw_at=*/19);
  RunOptions o;
  o.outdir = outdir("run_cut_short");
  o.observers = {&stopper};
  try {
    run_scenario(s, model, *backend, o);
    FAIL() << "the observer's error was swallowed";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
  }
  EXPECT_EQ(stopper.finishes, 1);
  const auto j = nlohmann::json::parse(read_text_file(o.outdir / "forces.json"));
  EXPECT_EQ(j["meta"]["completed"], false);
  EXPECT_EQ(j["meta"]["stop_reason"], "observer stop at tick 19");
  EXPECT_EQ(j["samples"]["t"].size(), 20u);  // ticks 0..19 were recorded
  EXPECT_EQ(j["samples"]["contacts"].size(), 20u);
}

TEST(RunLoop, NoForceLogWhenOutputsForcesIsFalse) {
  Scenario s = cube_scenario();
  s.time.duration = 0.01;
  s.outputs.forces = false;
  const Model model = cube_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), single_thread());
  RunOptions o;
  o.outdir = outdir("run_no_forces");
  const RunResult r = run_scenario(s, model, *backend, o);
  EXPECT_EQ(r.samples.size(), 10u);
  EXPECT_FALSE(fs::exists(o.outdir / "forces.json"));
}

}  // namespace
}  // namespace run_loop_test
}  // namespace organsim
