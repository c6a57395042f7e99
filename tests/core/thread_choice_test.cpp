// The thread choice during a run (core/sim/thread_choice.h): with made-up
// timings, never wall-clock ones, so these tests say the same on an idle and
// on a loaded machine.
#include <gtest/gtest.h>

#include <omp.h>

#include "core/sim/cpu_backend.h"
#include "core/sim/thread_choice.h"
#include "tests/core/test_models.h"

namespace organsim {
namespace thread_choice_test {
namespace {

constexpr int32_t kSubsteps = 10;

// Runs `ticks` ticks of kSubsteps steps through `choice`, each step on n
// threads costing step_cost(n, tick) seconds.
template <class Cost>
void run_ticks(ThreadChoice& choice, int32_t first_tick, int32_t ticks, Cost step_cost) {
  for (int32_t i = first_tick; i < first_tick + ticks; ++i) {
    int32_t steps = kSubsteps;
    if (choice.probe_due()) {
      choice.record_probe(step_cost(choice.other(), i));
      --steps;
    }
    choice.record_tick(steps, steps * step_cost(choice.chosen(), i));
  }
}

// Seconds per step on n threads: idle, two threads twice as fast as one;
// loaded, a two-thread step waits at its barriers for a thread that is not
// scheduled (30x slower), while one thread slows a little.
double idle(int32_t n) { return n == 2 ? 1e-4 : 2e-4; }
double loaded(int32_t n) { return n == 2 ? 3e-3 : 2.5e-4; }

// The machine changes from `before` to `after` at tick `at`.
auto change_at(int32_t at, double (*before)(int32_t), double (*after)(int32_t)) {
  return [=](int32_t n, int32_t tick) { return tick < at ? before(n) : after(n); };
}

TEST(ThreadChoice, SteadyMachineKeepsTheChoiceAndProbesEverMoreRarely) {
  ThreadChoice choice(2, 1);
  run_ticks(choice, 0, 1000, [](int32_t n, int32_t) { return idle(n); });
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.switches(), 0);
  // Probes after 16, then 32, 64, 128, 256, 512 more ticks (doubling):
  // ticks 16, 48, 112, 240, 496 and 1008 -> five within 1000 ticks.
  EXPECT_EQ(choice.probes(), 5);
}

TEST(ThreadChoice, LoadArrivingMidRunMovesTheRunToOneThreadWithinTheShortestInterval) {
  ThreadChoice choice(2, 1);
  const auto cost = change_at(300, idle, loaded);
  run_ticks(choice, 0, 300, cost);
  ASSERT_EQ(choice.chosen(), 2);
  // The slow ticks bring the probe forward: at most the shortest interval
  // (16 ticks) after the last probe, not the doubled one (256 by now).
  run_ticks(choice, 300, 17, cost);
  EXPECT_EQ(choice.chosen(), 1);
  EXPECT_EQ(choice.switches(), 1);
  // And it stays there while the load lasts (two-thread probes stay slow).
  run_ticks(choice, 317, 2000, cost);
  EXPECT_EQ(choice.chosen(), 1);
  EXPECT_EQ(choice.switches(), 1);
}

TEST(ThreadChoice, LoadLeavingMovesTheRunBackToTwoThreads) {
  // Chosen in a loaded moment: one thread; from tick 100 two threads are faster.
  ThreadChoice choice(1, 2);
  const auto cost = change_at(100, loaded, idle);
  run_ticks(choice, 0, 100, cost);
  ASSERT_EQ(choice.chosen(), 1);
  // The interval is at most 1024 ticks (max_interval), so within that the
  // next probe finds two threads faster.
  run_ticks(choice, 100, 1025, cost);
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.switches(), 1);
}

TEST(ThreadChoice, UnderLoadAFarSlowerOtherCountIsProbedEverMoreRarely) {
  ThreadChoice choice(1, 2);
  // One thread on a loaded machine: after a quiet first tick (the best),
  // every tick 2.4x slower (so the recent ticks ask for an early probe all
  // along); a two-thread step costs 20 one-thread steps.
  run_ticks(choice, 0, 1000, [](int32_t n, int32_t tick) { return n == 2 ? 5e-3 : (tick == 0 ? 2.5e-4 : 6e-4); });
  EXPECT_EQ(choice.chosen(), 1);
  // After each far slower probe the gap before an early one doubles (16,
  // 32, 64, ... ticks): 5 probes in 1000 ticks, where a fixed 16-tick gap
  // probes 62 times (measured by breaking the doubling).
  EXPECT_EQ(choice.probes(), 5);
}

// A tick slowed by another process's wake-up (a live session's client
// every millisecond) is not load: single ticks at 8x the best, one in 25,
// leave the probes on their doubling schedule (five in 1000 ticks, as on a
// steady machine) and the choice on two threads, where each would
// otherwise bring a probe forward (and a one-thread probe look faster).
TEST(ThreadChoice, ASingleSlowTickDoesNotBringAProbeForward) {
  ThreadChoice choice(2, 1);
  run_ticks(choice, 0, 1000, [](int32_t n, int32_t tick) { return idle(n) * (tick % 25 == 7 ? 8 : 1); });
  EXPECT_EQ(choice.switches(), 0);
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.probes(), 5);
}

// A switch made in a bad moment is undone at the shortest interval: on an
// idle machine the two-thread ticks from 40 to 47 are slowed to 2.5x (a
// client waking on the same cores), so the probe they bring forward
// switches to one thread; the next probe, 16 ticks later rather than the
// doubled interval (64), finds two threads faster again.
TEST(ThreadChoice, AMistakenSwitchIsUndoneAtTheShortestInterval) {
  ThreadChoice choice(2, 1);
  const auto cost = [](int32_t n, int32_t tick) { return n == 2 && tick >= 40 && tick < 48 ? 2.5e-4 : idle(n); };
  int32_t tick = 0;
  for (; choice.switches() == 0 && tick < 48; ++tick) run_ticks(choice, tick, 1, cost);
  ASSERT_EQ(choice.chosen(), 1) << "no switch by tick " << tick;
  run_ticks(choice, tick, 17, cost);
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.switches(), 2);
}

TEST(ThreadChoice, AProbeOnlyAsFastAsTheChoiceWithinTheMarginDoesNotSwitch) {
  ThreadChoice choice(2, 1);
  // One thread 5 % faster per step: within the 10 % margin, so no ping-pong.
  run_ticks(choice, 0, 500, [](int32_t n, int32_t) { return n == 2 ? 1e-4 : 0.95e-4; });
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_GT(choice.probes(), 0);
}

// A live loop (organsim serve) at dt 0.5 ms with a budget of 0.8 dt per
// step: one thread, leaving a core to the client, is kept while it fits,
// and never probes two threads meanwhile, though they are faster.
constexpr double kLiveBudget = 0.8 * 5e-4;

TEST(ThreadChoice, ALiveLoopKeepsTheFewerCountWithoutProbesWhileItsStepsFitTheBudget) {
  ThreadChoice choice(1, 2);
  choice.set_budget(kLiveBudget);
  run_ticks(choice, 0, 1000, [](int32_t n, int32_t) { return n == 2 ? 1.8e-4 : 3.5e-4; });
  EXPECT_EQ(choice.chosen(), 1);
  EXPECT_EQ(choice.probes(), 0);
}

// A slow moment of the machine (one thread's step 0.45 ms, every tick late
// on it) moves the loop to two threads within the shortest interval; when
// the machine is quick again (0.3 ms, within the budget with the margin to
// spare) a probe moves it back, within the longest interval.
TEST(ThreadChoice, ALiveLoopTakesTheMoreCountWhenTheFewerMissesTheBudgetAndReturnsWhenItFits) {
  ThreadChoice choice(1, 2);
  choice.set_budget(kLiveBudget);
  const auto cost = [](int32_t n, int32_t tick) { return n == 2 ? 2.5e-4 : (tick < 500 ? 4.5e-4 : 3e-4); };
  run_ticks(choice, 0, 17, cost);
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.switches(), 1);
  run_ticks(choice, 17, 483, cost);
  EXPECT_EQ(choice.chosen(), 2) << "a one-thread step over the budget is no reason to move back";
  run_ticks(choice, 500, 1025, cost);
  EXPECT_EQ(choice.chosen(), 1);
  EXPECT_EQ(choice.switches(), 2);
}

// Back to the fewer count only with the margin to spare: a one-thread step
// of 0.38 ms fits the 0.4 ms budget but not 0.9 of it, so the loop stays on
// two threads (no back and forth at the edge of the budget).
TEST(ThreadChoice, ALiveLoopOnTheMoreCountStaysWhenTheFewerOnlyJustFits) {
  ThreadChoice choice(1, 2);
  choice.set_budget(kLiveBudget);
  const auto cost = [](int32_t n, int32_t tick) { return n == 2 ? 2.5e-4 : (tick < 30 ? 4.5e-4 : 3.8e-4); };
  run_ticks(choice, 0, 30, cost);
  ASSERT_EQ(choice.chosen(), 2);
  run_ticks(choice, 30, 2000, cost);
  EXPECT_EQ(choice.chosen(), 2);
  EXPECT_EQ(choice.switches(), 1);
  EXPECT_GT(choice.probes(), 3);
}

// The backend with injected timings: two threads look fast at construction
// (a quiet moment) and slow from the 30th tick on. The run must end on one
// thread, say so, and give the very same positions as a one-thread run.
TEST(ThreadChoice, BackendSwitchesToOneThreadWhenTwoGetSlowAndResultsStayBitIdentical) {
  if (omp_get_max_threads() < 2) GTEST_SKIP() << "one hardware thread: nothing to choose";
  Material material;
  material.young_modulus = 4000;
  material.volume_modulus = 30000;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector base;  // held at its base, sagging under gravity
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  const Model model = build_model(testing::jittered_box(4, 0.05, 0.25, 1), material, options);
  int32_t tick = 0;
  const int32_t all = omp_get_max_threads();
  auto timing = [&](int32_t threads, int32_t steps, double) {
    const double per_step = threads == 1 ? 2e-4 : (tick < 30 ? 1e-4 : 5e-3);
    return steps * per_step;
  };
  auto adaptive = make_cpu_backend(model, {}, {Precision::Float, 0}, timing);
  EXPECT_NE(adaptive->device().find(std::to_string(all) + " threads (timed:"), std::string::npos)
      << adaptive->device();
  auto fixed = make_cpu_backend(model, {}, {Precision::Float, 1});
  TickRequest request;
  request.dt = 1e-4;
  request.substeps = kSubsteps;
  for (tick = 0; tick < 80; ++tick) {
    adaptive->tick(request);
    fixed->tick(request);
  }
  const std::string device = adaptive->device();
  EXPECT_NE(device.find("1 switch, now 1 thread"), std::string::npos) << device;
  std::vector<Vec3> xa, xf;
  adaptive->positions(xa);
  fixed->positions(xf);
  ASSERT_EQ(xa.size(), xf.size());
  bool moved = false;
  for (size_t i = 0; i < xa.size(); ++i) {
    ASSERT_EQ(xa[i], xf[i]) << "point " << i;  // bitwise: the step does not depend on the thread count
    moved = moved || xa[i] != model.rest_position[i];
  }
  EXPECT_TRUE(moved) << "the beam must sag under gravity for the comparison to mean anything";
}

// The backend in a live loop (CpuBackendOptions::live_share): it starts on
// all hardware threads but one (on two, without timing; on more, one
// against all but one, timed), keeps them while a step fits 0.8 dt, and
// takes the last one when the steps on the others get slower than that
// (injected timings: from the 30th tick); the results stay those of a fixed
// count, bit for bit.
TEST(ThreadChoice, BackendInALiveLoopTakesTheLastThreadWhenTheOthersMissTheBudget) {
  const int32_t all = omp_get_max_threads();
  if (all < 2) GTEST_SKIP() << "one hardware thread: nothing to choose";
  Material material;
  material.young_modulus = 4000;
  material.volume_modulus = 30000;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector base;
  base.kind = FixedSelector::Kind::Plane;
  base.point = Vec3(0, 0, 1e-9);
  base.normal = Vec3(0, 0, -1);
  options.fixed.push_back(base);
  const Model model = build_model(testing::jittered_box(4, 0.05, 0.25, 1), material, options);
  int32_t tick = 0;
  int32_t timed_at_construction = 0;
  auto timing = [&](int32_t threads, int32_t steps, double) {
    if (tick == 0) ++timed_at_construction;
    // Budget: 0.8 x 1e-4 s. On more than two, all but one beat one at construction.
    const double per_step = threads == all ? 5e-5 : tick < 30 ? (threads == 1 && all > 2 ? 2e-5 : 1e-5) : 5e-4;
    return steps * per_step;
  };
  CpuBackendOptions live{Precision::Float, 0};
  live.live_share = 0.8;
  auto adaptive = make_cpu_backend(model, {}, live, timing);
  if (all == 2) {
    EXPECT_EQ(timed_at_construction, 0) << "on two hardware threads a live loop starts on one without timing";
  }
  const std::string start = adaptive->device();
  EXPECT_NE(start.find(", " + std::to_string(all - 1) + " thread"), std::string::npos) << start;
  EXPECT_NE(start.find(" (live: " + std::to_string(all) + " while a step takes over 0.8 dt on " +
                       std::to_string(all - 1) + ")"),
            std::string::npos)
      << start;
  auto fixed = make_cpu_backend(model, {}, {Precision::Float, 1});
  TickRequest request;
  request.dt = 1e-4;
  request.substeps = kSubsteps;
  for (tick = 0; tick < 30; ++tick) adaptive->tick(request), fixed->tick(request);
  EXPECT_EQ(adaptive->device().find("re-timed"), std::string::npos) << "no probe while the steps fit";
  for (; tick < 80; ++tick) adaptive->tick(request), fixed->tick(request);
  const std::string device = adaptive->device();
  EXPECT_NE(device.find("1 switch, now " + std::to_string(all) + " threads"), std::string::npos) << device;
  std::vector<Vec3> xa, xf;
  adaptive->positions(xa);
  fixed->positions(xf);
  ASSERT_EQ(xa.size(), xf.size());
  for (size_t i = 0; i < xa.size(); ++i) ASSERT_EQ(xa[i], xf[i]) << "point " << i;
}

}  // namespace
}  // namespace thread_choice_test
}  // namespace organsim
