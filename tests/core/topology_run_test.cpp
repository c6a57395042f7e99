// Topology events in the run loop (issue 8): a hanging block cut right
// through drops its lower part in free fall, threaded and single-threaded
// runs stay bit-identical across cuts, and meta.events lists each change.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <filesystem>

#include "core/sim/cpu_backend.h"
#include "core/run/run.h"
#include "core/stability/critical_step.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "tests/core/forwarding_backend.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace topology_run_test {
namespace {

namespace fs = std::filesystem;

using testing::block_model;
using testing::hanging_block;

TEST(TopologyRun, BlockCutThroughDropsItsLowerPartWithG) {
  const Scenario s = hanging_block();
  const Model model = block_model(s);
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  testing::TopologyRecorder rec;
  rec.keep_positions = true;
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "topology_block_cut";
  options.observers = {&rec};
  const RunResult result = run_scenario(s, model, *backend, options);
  ASSERT_EQ(rec.changes, 1);
  ASSERT_TRUE(rec.last.has_value());
  const Model& cut = *rec.last;
  EXPECT_EQ(testing::topology_problems(cut), "");
  int32_t components = 0;
  const auto label = testing::point_components(cut, &components);
  ASSERT_EQ(components, 2);
  EXPECT_EQ(cut.npoint(), model.npoint() + 25);  // the 5 x 5 grid points of the plane z = 2 cm
  EXPECT_NEAR(cut.total_mass(), model.total_mass(), 1e-12 * model.total_mass());

  // The freed part: the component without fixed points.
  int32_t held_label = -1;
  for (int32_t p = 0; p < cut.npoint(); ++p)
    if (cut.fixed[p]) held_label = label[p];
  double mass = 0;
  for (int32_t p = 0; p < cut.npoint(); ++p)
    if (label[p] != held_label) mass += cut.mass[p];
  EXPECT_NEAR(mass, 0.5 * model.total_mass(), 1e-12 * model.total_mass());
  auto com_z = [&](size_t tick) {
    double z = 0;
    for (int32_t p = 0; p < cut.npoint(); ++p)
      if (label[p] != held_label) z += cut.mass[p] * rec.x[tick][p].z();
    return z / mass;
  };
  // From tick 25 (4 ms after the cut) to the end: the centre of mass of the
  // freed part accelerates at g. Internal forces cancel exactly in Verlet,
  // so this holds to round-off; 1 % is the bound.
  const size_t a = 25, b = 42, c = 59;
  ASSERT_EQ(rec.x.size(), 60u);
  ASSERT_EQ(rec.x[a].size(), static_cast<size_t>(cut.npoint()));
  const double h = (b - a) * s.time.tick();
  const double accel = (com_z(c) - 2 * com_z(b) + com_z(a)) / (h * h);
  EXPECT_NEAR(accel, -9.81, 0.01 * 9.81);

  // meta.events: one change at t = 20 ms with its counts.
  const auto log = nlohmann::json::parse(read_text_file(result.forces_path));
  const auto& events = log["meta"]["events"];
  ASSERT_EQ(events.size(), 1u);
  EXPECT_NEAR(events[0]["t"].get<double>(), 0.020, 1e-12);
  EXPECT_EQ(events[0]["kind"], "cut");
  EXPECT_EQ(events[0]["faces_separated"], 4 * 4 * 2);
  EXPECT_EQ(events[0]["points_added"], 25);
  EXPECT_EQ(events[0]["points"], cut.npoint());
  // The springs in the plane (40 grid edges, 16 face diagonals) are now one
  // per side; those reaching down from the plane moved to the copies.
  const int added = events[0]["springs_added"], removed = events[0]["springs_removed"];
  EXPECT_EQ(added - removed, 40 + 16);
  EXPECT_EQ(cut.nspring(), model.nspring() + 40 + 16);
  EXPECT_GT(removed, 0);
  EXPECT_EQ(log["samples"]["t"].size(), 60u);  // the samples continue across the change
}

TEST(TopologyRun, ThreadedRunIsBitIdenticalToSingleThreadedAcrossCuts) {
  Scenario s = hanging_block();
  // A second, crossing cut: partial, vertical, while the first one is open.
  CutEvent cross;
  cross.name = "cross";
  cross.keyframes = {{0.03, Vec3(0.025, -0.01, 0.05), Vec3(0.025, 0.05, 0.05)},
                     {0.04, Vec3(0.025, -0.01, 0.01), Vec3(0.025, 0.05, 0.01)}};
  s.events.cuts.push_back(cross);
  const Model model = block_model(s);
  std::vector<std::vector<Vec3>> finals;
  for (int threads : {1, 2}) {
    auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, threads});
    testing::TopologyRecorder rec;
    rec.keep_positions = true;
    RunOptions options;
    options.outdir = fs::path(ORGANSIM_TEST_TMP) / ("topology_threads_" + std::to_string(threads));
    options.observers = {&rec};
    run_scenario(s, model, *backend, options);
    EXPECT_GT(rec.changes, 1);
    finals.push_back(rec.x.back());
  }
  ASSERT_EQ(finals[0].size(), finals[1].size());
  for (size_t i = 0; i < finals[0].size(); ++i) ASSERT_EQ(finals[0][i], finals[1][i]) << "point " << i;
}

// Each tick's positions of the mesh's points (internal ids below the original count).
struct TickPositions : RunObserver {
  int32_t points = 0;
  std::vector<std::vector<Vec3>> x;
  std::vector<Vec3> all;
  void on_tick(const Model&, Backend& backend, const TickInfo&) override {
    backend.positions(all);
    x.emplace_back(all.begin(), all.begin() + points);
  }
};

struct BlockRun {
  TickPositions ticks;
  RunResult result;
};

BlockRun run_block(const Scenario& s, const Model& model, const std::string& name) {
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  BlockRun r;
  r.ticks.points = model.npoint();
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / name;
  options.observers = {&r.ticks};
  r.result = run_scenario(s, model, *backend, options);
  return r;
}

// The cut through the block over tick 20 with applied_at = 25 ms: made from
// tick 20's positions on a worker thread (the Model and the backend's
// tables) while ticks 20-24 step the uncut block, swapped in before tick 25. Replays of it must not depend on when
// the worker finishes.
TEST(TopologyRun, ACutOffTheTicksPathStepsTheOldModelUntilItsAppliedTick) {
  const Scenario at_once = hanging_block();
  Scenario later = at_once;
  later.events.cuts[0].applied_at = 0.025;
  Scenario uncut = at_once;
  uncut.events.cuts.clear();
  const Model model = block_model(at_once);
  const BlockRun a = run_block(at_once, model, "topology_off_path_at_once");
  const BlockRun b = run_block(later, model, "topology_off_path_later");
  const BlockRun b2 = run_block(later, model, "topology_off_path_later_again");
  const BlockRun u = run_block(uncut, model, "topology_off_path_uncut");

  const double tick = at_once.time.tick();
  const nlohmann::json& events = b.result.meta.extra["events"];
  ASSERT_EQ(events.size(), 1u) << events;
  EXPECT_EQ(events[0]["t"], 20 * tick);
  EXPECT_EQ(events[0]["applied_t"], 25 * tick);
  EXPECT_EQ(events[0]["points_added"], 25);
  EXPECT_FALSE(a.result.meta.extra["events"][0].contains("applied_t"));
  // The backend's tables were prepared on the worker too (Backend::prepare),
  // so only their adoption was on the tick's path; the cut at once did both there.
  EXPECT_TRUE(events[0].contains("backend_prepare_ms")) << events[0];
  EXPECT_FALSE(a.result.meta.extra["events"][0].contains("backend_prepare_ms"));
  ASSERT_EQ(b.ticks.x.size(), 60u);
  // Ticks 0-24 (ending at 1..25 ms) step the uncut block exactly; the cut at
  // once has changed tick 20 already; from tick 25 on the block falls apart.
  for (size_t k = 0; k < 25; ++k) ASSERT_EQ(b.ticks.x[k], u.ticks.x[k]) << "tick " << k;
  EXPECT_NE(a.ticks.x[20], u.ticks.x[20]);
  EXPECT_NE(b.ticks.x[30], u.ticks.x[30]);
  EXPECT_NE(b.ticks.x[30], a.ticks.x[30]);
  for (size_t k = 0; k < 60; ++k) ASSERT_EQ(b.ticks.x[k], b2.ticks.x[k]) << "tick " << k;
  EXPECT_EQ(b.result.meta.extra["final_points"], a.result.meta.extra["final_points"]);
}

// The nice value of the calling thread (Linux keeps one per thread).
int this_threads_nice() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }

// Records the nice value and scheduling policy of the thread that prepares
// a change's tables.
class NiceOfPrepare final : public test::ForwardingBackend {
 public:
  using ForwardingBackend::ForwardingBackend;
  mutable int nice = -100, policy = -1;
  std::unique_ptr<PreparedModel> prepare(const Model& next) const override {
    nice = this_threads_nice();
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy, &param);
    return inner_->prepare(next);
  }
};

// hanging_block with its cut built off the tick's path, going in at 25 ms:
// the nice value and policy of the worker's thread as it prepared the
// tables.
struct WorkerThread {
  int nice = -100, policy = -1;
};
WorkerThread run_a_cut_off_the_ticks_path(const std::string& name) {
  Scenario later = hanging_block();
  later.events.cuts[0].applied_at = 0.025;
  const Model model = block_model(later);
  NiceOfPrepare backend(make_cpu_backend(model, backend_tool(later), {Precision::Double, 1}));
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / name;
  const RunResult result = run_scenario(later, model, backend, options);
  EXPECT_EQ(result.meta.extra["events"][0]["applied_t"], 25 * later.time.tick());
  return {backend.nice, backend.policy};
}

// The worker that makes a change off the tick's path runs at the lowest
// priority (nice 19), so that on a machine whose cores the run loop and a
// live client share it takes idle time, not the ticks'; the loop's own
// thread keeps its priority.
TEST(TopologyRun, TheWorkerOffTheTicksPathYieldsToTheRunLoop) {
  const int loop_nice = this_threads_nice();
  EXPECT_EQ(run_a_cut_off_the_ticks_path("topology_off_path_nice").nice, 19);
  EXPECT_EQ(this_threads_nice(), loop_nice);
}

// Under organsim serve --realtime-priority the loop's thread runs
// SCHED_FIFO; the worker it starts must not inherit that (it would take
// the ticks' core for a whole rebuild): it returns to the normal policy at
// nice 19.
TEST(TopologyRun, TheWorkerLeavesTheLoopsRealTimePolicy) {
  sched_param fifo{};
  fifo.sched_priority = 1;
  if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &fifo) != 0)
    GTEST_SKIP() << "SCHED_FIFO is not permitted here (it needs CAP_SYS_NICE)";
  const WorkerThread worker = run_a_cut_off_the_ticks_path("topology_off_path_fifo");
  const sched_param normal{};
  ASSERT_EQ(pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal), 0);
  EXPECT_EQ(worker.policy, SCHED_OTHER);
  EXPECT_EQ(worker.nice, 19);
}

TEST(TopologyRun, DtAboveTheNewDtCritStopsTheRunWithANumericalError) {
  // run_scenario leaves the check before a run to its caller, so a dt 1.5 x
  // dt_crit gets as far as the first change, at the first tick (before any
  // step could blow up); the check after the change must refuse it.
  Scenario s = hanging_block();
  s.events.cuts[0].keyframes[0].t = 0.0;
  s.events.cuts[0].keyframes[1].t = 0.001;
  const Model model = block_model(s);
  s.time.dt = 1.5 * estimate_critical_step(model).dt_crit;
  s.time.substeps = 1;
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "topology_dt_check";
  try {
    run_scenario(s, model, *backend, options);
    ADD_FAILURE() << "ran with dt above dt_crit after a change";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Numerical);
    EXPECT_NE(std::string(e.what()).find("after the topology change at t = 0"), std::string::npos) << e.what();
  }
  // The log is still written, with the change and the dt_crit that refused it.
  const auto log = nlohmann::json::parse(read_text_file(options.outdir / "forces.json"));
  EXPECT_EQ(log["meta"]["completed"], false);
  ASSERT_EQ(log["meta"]["events"].size(), 1u);
  // dt is above the guaranteed step, so the full estimate decided.
  EXPECT_EQ(log["meta"]["events"][0]["dt_check"], "power iteration");
  EXPECT_LT(log["meta"]["events"][0]["dt_crit_guaranteed"].get<double>(), s.time.dt);
  EXPECT_LT(log["meta"]["events"][0]["dt_crit"].get<double>(), s.time.dt);
  // With allow_unstable the run goes on (and only warns).
  auto again = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  options.allow_unstable = true;
  s.time.duration = 0.002;
  EXPECT_NO_THROW(run_scenario(s, model, *again, options));
}

// The same change built off the tick's path (applied_at two ticks later):
// the worker makes the full estimate as well as the Model, so that at 28k
// points the second of power iteration never lands on a tick. The tick it
// goes in at only reads the decision, which stops the run the same way with
// the same dt_crit.
TEST(TopologyRun, OffTheTicksPathTheWorkerMakesTheFullDtEstimate) {
  Scenario s = hanging_block();
  const Model model = block_model(s);
  s.time.dt = 1.5 * estimate_critical_step(model).dt_crit;
  s.time.substeps = 1;
  s.events.cuts[0].keyframes[0].t = 0.0;
  s.events.cuts[0].keyframes[1].t = 0.5 * s.time.dt;  // within the first tick
  auto run_until_refused = [&](const Scenario& scenario, const std::string& name) {
    auto backend = make_cpu_backend(model, backend_tool(scenario), {Precision::Double, 1});
    RunOptions options;
    options.outdir = fs::path(ORGANSIM_TEST_TMP) / name;
    EXPECT_THROW(run_scenario(scenario, model, *backend, options), Error) << name;
    return nlohmann::json::parse(read_text_file(options.outdir / "forces.json"))["meta"]["events"].at(0);
  };
  const nlohmann::json on_path = run_until_refused(s, "topology_dt_check_on_path");
  s.events.cuts[0].applied_at = 2 * s.time.dt;
  const nlohmann::json off_path = run_until_refused(s, "topology_dt_check_off_path");
  EXPECT_EQ(off_path["applied_t"], 2 * s.time.dt) << off_path;
  EXPECT_EQ(off_path["dt_check"], "power iteration");
  EXPECT_EQ(off_path["dt_crit"], on_path["dt_crit"]);  // the same Model, the same estimate
  EXPECT_LT(off_path["dt_crit"].get<double>(), s.time.dt);
  // Timed on the worker; nothing of it on the tick's path.
  EXPECT_TRUE(off_path.contains("dt_check_prepare_ms")) << off_path;
  EXPECT_EQ(off_path["dt_check_ms"], 0.0);
  EXPECT_FALSE(on_path.contains("dt_check_prepare_ms")) << on_path;
  EXPECT_GT(on_path["dt_check_ms"].get<double>(), 0.0);
}

}  // namespace
}  // namespace topology_run_test
}  // namespace organsim
