// Sutures (issue 8): tension-only springs on a tightening schedule, tied
// between ticks through the rebuild path. The gap across a cut closes with
// a bounded force and no NaN; a slack or closing suture exerts no force; the
// kernel and the reference backend agree with the reference force; threads
// change no bit; mass and the invariants hold; models with sutures run on
// the simd kernel; errors
// found during the run name the event and field.
#include <gtest/gtest.h>

#include <filesystem>
#include <random>

#include "core/model/model_rebuild.h"
#include "core/sim/cpu_backend.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "core/stability/step_after_change.h"
#include "core/util/error.h"
#include "tests/core/suture_test_util.h"
#include "tests/core/test_models.h"
#include "tests/core/topology_test_util.h"

namespace organsim {
namespace suture_test {
namespace {

namespace fs = std::filesystem;

RunResult run_recorded(const Scenario& s, const Model& model, const CpuBackendOptions& options,
                       testing::TopologyRecorder& rec, const std::string& name) {
  auto backend = make_cpu_backend(model, backend_tool(s), options);
  RunOptions run;
  run.outdir = fs::path(ORGANSIM_TEST_TMP) / name;
  run.observers = {&rec};
  return run_scenario(s, model, *backend, run);
}

std::vector<Vec3> final_positions(const Scenario& s, const Model& model, const CpuBackendOptions& options,
                                  const std::string& name) {
  testing::TopologyRecorder rec;
  rec.keep_positions = true;
  run_recorded(s, model, options, rec, name);
  return rec.x.back();
}

// Tension of every suture of `model` at positions x and time t, N (no damper).
double largest_tension(const Model& model, const std::vector<Vec3>& x, double t) {
  double most = 0;
  for (const Suture& u : model.sutures) {
    if (u.ends[1] >= static_cast<int32_t>(x.size())) continue;
    most = std::max(most, u.k * std::max(0.0, (x[u.ends[1]] - x[u.ends[0]]).norm() - u.rest_at(t)));
  }
  return most;
}

TEST(Suture, GapAcrossACutClosesWithBoundedForceAndNoNaN) {
  const Scenario s = testing::sutured_beam(0.3, 1.3);
  const Model model = testing::beam_model(s);
  testing::TopologyRecorder rec;
  rec.keep_positions = true;
  const RunResult result = run_recorded(s, model, {Precision::Double, 1}, rec, "suture_beam");
  ASSERT_TRUE(rec.last.has_value());
  const Model& last = *rec.last;
  ASSERT_GT(last.nsuture(), 2);
  EXPECT_EQ(testing::topology_problems(last), "");
  // A suture adds no mass: the cut's copies and the sutures leave it to 1e-12.
  EXPECT_NEAR(last.total_mass(), model.total_mass(), 1e-12 * model.total_mass());
  const auto& events = result.meta.extra["events"];
  ASSERT_EQ(events.back()["kind"], "suture");
  EXPECT_EQ(events.back()["sutures_added"], last.nsuture());
  EXPECT_DOUBLE_EQ(events.back()["t"].get<double>(), 0.3);

  // Tick i ends at (i + 1) ms; the sutures are tied at the start of tick 300.
  const size_t tie = 300;
  const double opening = testing::cut_gap(last, rec.x[tie - 1]);
  ASSERT_GT(opening, 2e-3) << "the cut must open before it can be closed";
  // Every rest length reaches zero by the tie + opening / rate (5 cm/s); the
  // gap must be at most 10 % of the opening 0.2 s after that (the tissue
  // follows, damped) and stay so to the end (10^4 steps after the tie).
  const size_t closed = tie + static_cast<size_t>(1e3 * (opening / 0.05 + 0.2));
  ASSERT_LT(closed, rec.x.size());
  double max_tension = 0;
  for (size_t i = 0; i < rec.x.size(); ++i) {
    for (const Vec3& p : rec.x[i]) ASSERT_TRUE(p.allFinite()) << "tick " << i;
    const double gap = testing::cut_gap(last, rec.x[i]);
    if (i >= closed) {
      EXPECT_LE(gap, 0.1 * opening) << "t = " << (i + 1) * 1e-3 << " s";
    }
    max_tension = std::max(max_tension, largest_tension(last, rec.x[i], static_cast<double>(i + 1) * 1e-3));
  }
  // Bounded: no suture ever pulls harder than its stiffness times the
  // opening it was tied across (what it would pull if the tissue did not
  // move at all); an overshooting or unstable closure would exceed it.
  double k_max = 0;
  for (const Suture& u : last.sutures) k_max = std::max(k_max, u.k);
  EXPECT_GT(max_tension, 0);
  EXPECT_LE(max_tension, k_max * opening);
  std::cout << "opening " << opening << " m, final gap " << testing::cut_gap(last, rec.x.back())
            << " m, largest tension " << max_tension << " N (bound " << k_max * opening << " N)\n";
}

// A model with one suture between two far points of the beam; the same
// model without it for comparison.
struct SutureCase {
  Model plain, sutured;
  int32_t a = 0, b = 0;
};

SutureCase one_suture(double length_factor) {
  SutureCase c;
  const Scenario s = testing::sutured_beam();
  c.plain = testing::beam_model(s);
  c.a = 0;
  c.b = c.plain.npoint() - 1;
  Suture u;
  u.ends = {c.a, c.b};
  u.k = 300;
  u.length = length_factor * (c.plain.rest_position[c.b] - c.plain.rest_position[c.a]).norm();
  c.sutured = add_sutures(c.plain, {u});
  return c;
}

// One step of each backend from x with x_prev.
std::vector<Vec3> one_step(std::unique_ptr<Backend> backend, const std::vector<Vec3>& x,
                           const std::vector<Vec3>& x_prev) {
  backend->set_state(x, x_prev);
  testing::run_ticks(*backend, 1, 1e-4, 1);
  std::vector<Vec3> out;
  backend->positions(out);
  return out;
}
std::vector<Vec3> one_step(const Model& model, const CpuBackendOptions& options, const std::vector<Vec3>& x,
                           const std::vector<Vec3>& x_prev) {
  return one_step(make_cpu_backend(model, {}, options), x, x_prev);
}

TEST(Suture, PullsWhenTautAndNeverWhenSlackOrClosing) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0, 1e-4);
  for (const Precision precision : {Precision::Double, Precision::Float}) {
    for (const double factor : {1.5, 0.5}) {  // slack, taut
      for (const double closing : {0.0, 1.0}) {  // at rest; ends closing at 2 m/s
        const SutureCase c = one_suture(factor);
        std::vector<Vec3> x = c.plain.rest_position, x_prev = x;
        for (Vec3& p : x) p += Vec3(noise(rng), noise(rng), noise(rng));
        x_prev = x;
        const Vec3 axis = (x[c.b] - x[c.a]).normalized();
        // Closing at 100 m/s: the damper's d v = 0.3 N s/m x 200 m/s = 60 N
        // outweighs the taut pull k (L - r) = 300 N/m x 4.2 cm = 13 N, so a
        // damper acting alone would push.
        const Vec3 step = closing * 1e-2 * axis;
        x_prev[c.a] -= step;
        x_prev[c.b] += step;
        const auto with = one_step(c.sutured, {precision, 1}, x, x_prev);
        const auto without = one_step(c.plain, {precision, 1}, x, x_prev);
        // Reference: the suture's force on a.
        std::vector<Vec3> fw, fo, v(x.size());
        for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev[i]) / 1e-4;
        reference_internal_forces(c.sutured, x, v, fw);
        reference_internal_forces(c.plain, x, v, fo);
        const Vec3 pull_on_a = fw[c.a] - fo[c.a];
        const bool should_pull = factor < 1 && closing == 0;
        if (should_pull) {
          EXPECT_GT(pull_on_a.dot(axis), 1.0);  // 300 N/m x ~4 cm
          EXPECT_NE(with[c.a], without[c.a]);
        } else {
          // Slack, or taut but closing so fast that k (L - r) + d v < 0:
          // exactly no force, so exactly the same step, bit for bit.
          EXPECT_EQ(pull_on_a, Vec3::Zero()) << factor << " " << closing;
          for (size_t i = 0; i < with.size(); ++i) ASSERT_EQ(with[i], without[i]) << "point " << i;
        }
      }
    }
  }
}

// The CPU kernels in double and float against the double reference, for
// sutures taut and slack, tightened by a schedule that started before the
// step (so the backend's per-tick rest length is what is compared).
TEST(Suture, CpuKernelsMatchTheReferenceWithTighteningSutures) {
  const Scenario s = testing::sutured_beam();
  const Model plain = testing::beam_model(s);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int32_t> pick(0, plain.npoint() - 1);
  std::vector<Suture> sutures;
  for (int k = 0; k < 12; ++k) {
    int32_t a = pick(rng), b = pick(rng);
    if (a == b) continue;
    Suture u;
    u.ends = {std::min(a, b), std::max(a, b)};
    u.k = 200;
    u.length = (k % 2 ? 1.2 : 0.9) * (plain.rest_position[b] - plain.rest_position[a]).norm();
    u.tied_at = -0.1;  // tightened for 0.1 s at 2 cm/s by the first tick: 2 mm shorter
    u.rate = 0.02;
    sutures.push_back(u);
  }
  const Model model = add_sutures(plain, sutures);
  std::normal_distribution<double> noise(0, 2e-3);
  std::vector<Vec3> x = model.rest_position, x_prev = x;
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] += Vec3(noise(rng), noise(rng), noise(rng));
    x_prev[i] = x[i] + 1e-3 * Vec3(noise(rng), noise(rng), noise(rng));
  }
  const double dt = 1e-4;
  std::vector<Vec3> f, v(x.size());
  for (size_t i = 0; i < x.size(); ++i) v[i] = (x[i] - x_prev[i]) / dt;
  reference_internal_forces(model, x, v, f, 0.0);
  double largest = 0;
  std::vector<Vec3> want(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const Vec3 d = model.inv_mass[i] > 0 ? Vec3((1 - model.viscous_damping * dt) * (x[i] - x_prev[i]) +
                                                dt * dt * model.inv_mass[i] * f[i])
                                         : Vec3::Zero();
    want[i] = x[i] + d;
    largest = std::max(largest, d.norm());
  }
  // The reference backend, and the kernel in both precisions. Double: the
  // same sums in another order, 1e-9 of the step's largest increment.
  // Float: positions of ~8 cm round at 4e-9 m, against increments of
  // ~1e-3 m here: 1e-4 of the increment.
  const auto error = [&](const std::vector<Vec3>& got) {
    double err = 0;
    for (size_t i = 0; i < x.size(); ++i) err = std::max(err, (got[i] - want[i]).norm());
    return err;
  };
  EXPECT_LT(error(one_step(make_reference_backend(model, {}, Integrator::Verlet), x, x_prev)), 1e-9 * largest)
      << "reference";
  EXPECT_LT(error(one_step(model, {Precision::Double, 1}, x, x_prev)), 1e-9 * largest) << "kernel, double";
  EXPECT_LT(error(one_step(model, {Precision::Float, 1}, x, x_prev)), 1e-4 * largest) << "kernel, float";
  // The schedule matters: with rest lengths when tied, the step differs.
  std::vector<Vec3> f_tied;
  reference_internal_forces(model, x, v, f_tied, -0.1);
  double differs = 0;
  for (size_t i = 0; i < x.size(); ++i) differs = std::max(differs, (f_tied[i] - f[i]).norm());
  EXPECT_GT(differs, 0.1);
}

TEST(Suture, ThreadedRunIsBitIdenticalAndFloatFollowsDouble) {
  const Scenario s = testing::sutured_beam(0.05, 0.25);
  const Model model = testing::beam_model(s);
  const auto one = final_positions(s, model, {Precision::Double, 1}, "suture_threads_1");
  const auto two = final_positions(s, model, {Precision::Double, 2}, "suture_threads_2");
  const auto flt = final_positions(s, model, {Precision::Float, 1}, "suture_float");
  ASSERT_EQ(one.size(), two.size());
  ASSERT_EQ(one.size(), flt.size());
  double worst = 0, moved = 0;
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one[i], two[i]) << "point " << i;
    worst = std::max(worst, (flt[i] - one[i]).norm());
    if (static_cast<int32_t>(i) < model.npoint()) moved = std::max(moved, (one[i] - model.rest_position[i]).norm());
  }
  ASSERT_GT(moved, 1e-3);
  // 2500 float steps with a cut and sutures tied on the float positions:
  // rounding of ~1e-9 m per step accumulates (measured 1.5 um); tolerance
  // 1e-4 of the 8 cm beam (8 um) against 2 cm of sag.
  EXPECT_LT(worst, 1e-4 * 0.08);
}

TEST(Suture, AddingSuturesKeepsMassAndInvariantsAndALaterCutKeepsThem) {
  const SutureCase c = one_suture(0.5);
  EXPECT_EQ(c.sutured.version, c.plain.version + 1);
  EXPECT_EQ(c.sutured.mass, c.plain.mass);  // bit for bit: the same tets' shares
  EXPECT_EQ(c.sutured.nspring(), c.plain.nspring() + 1);
  EXPECT_EQ(c.sutured.first_suture(), c.plain.nspring());
  EXPECT_EQ(testing::topology_problems(c.sutured), "");
  // A through cut at x = 5 cm afterwards: the suture stays, on the same ids.
  const Model cut = rebuild_model(c.sutured, testing::split_across_plane_x(c.sutured, 0.05));
  ASSERT_EQ(cut.nsuture(), 1);
  EXPECT_EQ(cut.sutures[0].ends, (Edge{c.a, c.b}));
  EXPECT_EQ(cut.spring_ends.back(), (Edge{c.a, c.b}));
  EXPECT_EQ(testing::topology_problems(cut), "");
  EXPECT_NEAR(cut.total_mass(), c.plain.total_mass(), 1e-12 * c.plain.total_mass());
  // Malformed sutures are refused.
  Suture same_point;
  same_point.ends = {3, 3};
  same_point.k = 1;
  EXPECT_THROW(add_sutures(c.plain, {same_point}), Error);
  Suture no_k;
  no_k.ends = {1, 2};
  EXPECT_THROW(add_sutures(c.plain, {no_k}), Error);
}

TEST(Suture, ModelsWithSuturesRunOnTheSimdKernel) {
  const SutureCase c = one_suture(0.5);
  EXPECT_EQ(simd_kernel_unsupported(c.sutured), "");
  const std::string kernel = "simd (" + default_simd_target().name + ") kernel";
  for (Precision precision : {Precision::Float, Precision::Double}) {
    const auto backend = make_cpu_backend(c.sutured, {}, {precision, 1});
    EXPECT_NE(backend->device().find(kernel), std::string::npos) << backend->device();
    const std::string springs = backend->plan().passes[0].detail;
    EXPECT_NE(springs.find("1 of them sutures"), std::string::npos) << springs;
    // A backend keeps its kernel when sutures are added (Backend::rebuild), with the same state.
    auto moving = make_cpu_backend(c.plain, {}, {precision, 1});
    testing::run_ticks(*moving, 3, 1e-4, 2);
    std::vector<Vec3> before, after;
    moving->positions(before);
    moving->rebuild(c.sutured);
    moving->positions(after);
    EXPECT_EQ(before, after);
    EXPECT_NE(moving->device().find(kernel), std::string::npos) << moving->device();
  }
}

// The run's dt check after a change keeps its Gershgorin rows and recomputes
// only the touched ones: tying sutures must recompute their ends' rows (a
// stiff suture on a light point lowers the guaranteed step), exactly as a
// fresh computation gives them.
TEST(Suture, TheDtCheckAfterTyingSuturesSeesTheirStiffness) {
  const SutureCase c = one_suture(0.5);
  ChangeStepCheck check(c.plain);
  const double before = check.guaranteed_step(c.plain, {});
  Suture stiff = c.sutured.sutures[0];
  stiff.k = 1e5;  // N/m on points of 1e-4 kg: far stiffer than the tissue
  const Model next = add_sutures(c.plain, {stiff});
  check.update(c.plain, next);
  const GershgorinRows fresh = gershgorin_rows_with_scale(next, check.rows().scale);
  EXPECT_EQ(check.rows().all, fresh.all);
  EXPECT_EQ(check.rows().damped, fresh.damped);
  EXPECT_LT(check.guaranteed_step(next, {}), 0.5 * before);
}

std::string run_error(const Scenario& s, const std::string& name) {
  const Model model = testing::beam_model(s);
  testing::TopologyRecorder rec;
  try {
    run_recorded(s, model, {Precision::Double, 1}, rec, name);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "ran without error";
  return "";
}

TEST(Suture, ErrorsFoundDuringTheRunNameTheEventAndField) {
  Scenario far = testing::sutured_beam(0.05, 0.06);
  far.events.sutures[0].max_distance = 1e-6;  // the cut has opened by more than a micrometre
  const std::string e1 = run_error(far, "suture_error_far");
  EXPECT_NE(e1.find("events[1].suture.max_distance: point "), std::string::npos) << e1;
  EXPECT_NE(e1.find("has no partner within 1e-06 m"), std::string::npos) << e1;

  Scenario out_of_range = testing::sutured_beam(0.02, 0.03);
  out_of_range.events.sutures[0].along.clear();
  out_of_range.events.sutures[0].pairs = {{0, 1}, {2, 100000}};
  const std::string e2 = run_error(out_of_range, "suture_error_range");
  EXPECT_NE(e2.find("events[1].suture.pairs[1][1]: point 100000 out of range"), std::string::npos) << e2;

  Scenario missed = testing::sutured_beam(0.02, 0.03);
  for (BladeKeyframe& k : missed.events.cuts[0].keyframes) {  // the blade passes above the beam
    k.a.z() += 0.1;
    k.b.z() += 0.1;
  }
  const std::string e3 = run_error(missed, "suture_error_missed");
  EXPECT_NE(e3.find("events[1].suture.along: the cut \"incision\" has separated no points"), std::string::npos) << e3;
}

TEST(Suture, ExplicitPairsAreTiedInInputNumbering) {
  Scenario s = testing::sutured_beam(0.02, 0.03);
  const Model model = testing::beam_model(s);
  SutureEvent& u = s.events.sutures[0];
  u.along.clear();
  u.pairs = {{0, 5}, {7, 2}};
  u.length = 0.01;
  testing::TopologyRecorder rec;
  run_recorded(s, model, {Precision::Double, 1}, rec, "suture_pairs");
  ASSERT_TRUE(rec.last.has_value());
  const Model& last = *rec.last;
  ASSERT_EQ(last.nsuture(), 2);
  for (int k = 0; k < 2; ++k) {
    const Edge ends = last.sutures[k].ends;
    Edge input{last.input_of_internal[ends[0]], last.input_of_internal[ends[1]]};
    std::sort(input.begin(), input.end());
    Edge want{u.pairs[k][0], u.pairs[k][1]};
    std::sort(want.begin(), want.end());
    EXPECT_EQ(input, want);
    EXPECT_DOUBLE_EQ(last.sutures[k].length, 0.01);
    EXPECT_DOUBLE_EQ(last.sutures[k].tied_at, 0.02);
    // Scaled like the tool's stiffness by the lighter end (Model::tool_scale).
    EXPECT_DOUBLE_EQ(last.sutures[k].k, 300 * std::min(last.tool_scale(ends[0]), last.tool_scale(ends[1])));
  }
}

}  // namespace
}  // namespace suture_test
}  // namespace organsim
