// Blow-up detection during a run: each check fires on its own symptom, names
// the point in input numbering, stays quiet on a stable run, and the run loop
// keeps a valid force log that says why the run stopped.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/scenario/scenario.h"
#include "core/run/run.h"
#include "core/stability/blowup_monitor.h"
#include "core/util/error.h"
#include "tests/core/forwarding_backend.h"
#include "tests/core/stability_test_util.h"

namespace organsim {
namespace stability_blowup_test {
namespace {

// Ticks the backend with the monitor attached; returns the error message, or
// "" when all ticks passed.
std::string run_with_monitor(const Model& model, Backend& backend, BlowupMonitor& monitor, double dt,
                             int substeps, int ticks) {
  monitor.on_start(model, backend);
  TickRequest request;
  request.dt = dt;
  request.substeps = substeps;
  for (int i = 0; i < ticks; ++i) {
    TickInfo info;
    info.tick = i;
    info.reaction = backend.tick(request);
    info.t = backend.time();
    try {
      monitor.on_tick(model, backend, info);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Numerical);
      return e.what();
    }
  }
  return "";
}

Model sagging_box() {
  Material m = testing::undamped_material(3000, 1e4);
  m.spring_damping_time = 0.001;
  m.viscous_damping = 2;
  TetMesh mesh = testing::jittered_box(3, 0.03, 0.2, 4);
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Plane;
  bottom.point = Vec3(0, 0, 1e-9);
  bottom.normal = Vec3(0, 0, -1);
  options.fixed.push_back(bottom);
  return build_model(mesh, m, options);
}

// A damped box sagging under gravity at 0.9 dt_crit for 0.3 s: no finding.
// Gravity does work here (KE > 0 from rest), so this also checks the budget.
TEST(StabilityBlowup, StableSagIsQuiet) {
  const Model model = sagging_box();
  const StabilityReport r = estimate_critical_step(model);
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  BlowupMonitor monitor({}, {0.9 * r.dt_crit, 0, 0, r});
  const int substeps = 10;
  const int ticks = static_cast<int>(0.3 / (0.9 * r.dt_crit * substeps));
  EXPECT_EQ(run_with_monitor(model, *backend, monitor, 0.9 * r.dt_crit, substeps, ticks), "");
  EXPECT_EQ(monitor.checks(), ticks);
}

// Undamped box at 1.3 dt_crit from a tiny perturbation: stopped while every
// position is still finite (energy or strain first), with time, point and
// the dt_crit cause in the message.
TEST(StabilityBlowup, UnstableStepIsStoppedEarly) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material());
  const StabilityReport r = estimate_critical_step(model);
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  std::vector<Vec3> x = model.rest_position;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) x[i] += 1e-9 * Vec3(std::sin(i), std::cos(3 * i), std::sin(7 * i));
  backend->set_state(x, x);
  const double dt = 1.3 * r.dt_crit;
  BlowupMonitor monitor({}, {dt, 0, 0, r});
  const std::string msg = run_with_monitor(model, *backend, monitor, dt, 5, 2000);
  ASSERT_NE(msg, "");
  EXPECT_NE(msg.find("run stopped at t = "), std::string::npos) << msg;
  EXPECT_NE(msg.find("(input numbering)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("exceeds dt_crit"), std::string::npos) << msg;
  EXPECT_EQ(msg.find("non-finite"), std::string::npos) << msg;
  std::vector<Vec3> now;
  backend->positions(now);
  for (const Vec3& p : now) EXPECT_TRUE(p.allFinite());
}

// Each geometric check names the right point, in input numbering (the
// model's internal order differs from the input's).
TEST(StabilityBlowup, GeometryChecksNameThePoint) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material());
  // A free interior input point; internal ids differ.
  const int32_t input = 21;
  const int32_t internal = model.internal_of_input[input];
  ASSERT_FALSE(model.fixed[internal]);
  BlowupMonitorOptions options;

  std::vector<Vec3> x = model.rest_position;
  x[internal].y() = std::numeric_limits<double>::quiet_NaN();
  auto f = check_geometry(model, x, options);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, BlowupFinding::Kind::NonFinite);
  EXPECT_EQ(f->point, input);

  x = model.rest_position;
  x[internal] += Vec3(0.05, 0, 0);  // 5 cells away: springs at 21 stretch by > 100 %
  f = check_geometry(model, x, options);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, BlowupFinding::Kind::Strain);
  EXPECT_EQ(f->point, input);
  EXPECT_GT(f->value, 1.0);

  x = model.rest_position;
  x[internal] += Vec3(0.012, 0.012, 0.012);  // through its neighbours' faces, strain < 100 %
  options.max_strain = 10;
  options.max_inversion = 0;  // any inversion counts here
  f = check_geometry(model, x, options);
  ASSERT_TRUE(f);
  EXPECT_EQ(f->kind, BlowupFinding::Kind::Inversion);
  EXPECT_EQ(f->point, input);
  EXPECT_LT(f->value, 0.0);

  // A slightly inverted tet (a sliver pushed just through) is within the default bound.
  x = model.rest_position;
  x[internal] += Vec3(0.0101, 0.0101, 0.0101);  // just past the lattice point (2,2,2) cells away
  BlowupMonitorOptions defaults;
  defaults.max_strain = 10;
  EXPECT_FALSE(check_geometry(model, x, defaults));
  EXPECT_FALSE(check_geometry(model, model.rest_position, options));
  EXPECT_NEAR(elastic_energy(model, model.rest_position), 0.0, 1e-18);  // rest state stores nothing
}

// With a check every 10 ticks, the springs and tets are checked a tenth per
// tick (so no tick of a live session pays for the whole pass), and a spring
// stretched beyond the bound still stops the run within the ten ticks that
// follow the positions being read.
TEST(StabilityBlowup, GeometryPassIsSpreadOverTheIntervalAndStillFindsAStretchedSpring) {
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material());
  BlowupMonitorOptions options;
  options.interval_ticks = 10;
  options.energy_factor = 1e30;  // the geometric checks alone
  const int64_t items = model.first_suture() + model.ntet();
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  const double dt = 0.5 * estimate_critical_step(model).dt_crit;
  BlowupMonitor quiet(options, {dt, 0, 0, std::nullopt});
  EXPECT_EQ(run_with_monitor(model, *backend, quiet, dt, 1, 30), "");
  EXPECT_EQ(quiet.checks(), 3);
  EXPECT_GT(quiet.largest_tick_scan(), 0);
  EXPECT_LE(quiet.largest_tick_scan(), items / 10 + 2) << items << " springs and tets";

  // A free interior point moved 10 cells: its springs stretch about tenfold (bound 400 %).
  const int32_t internal = model.internal_of_input[21];
  ASSERT_FALSE(model.fixed[internal]);
  std::vector<Vec3> x = model.rest_position;
  x[internal] += Vec3(0.1, 0, 0);
  auto stretched = make_cpu_backend(model, {}, testing::one_thread());
  stretched->set_state(x, x);
  BlowupMonitor monitor(options, {dt, 0, 0, std::nullopt});
  monitor.on_start(model, *stretched);
  TickRequest request;
  request.dt = dt;
  int stopped_at = -1;
  std::string msg;
  for (int i = 0; i < 40 && stopped_at < 0; ++i) {
    TickInfo info;
    info.tick = i;
    info.reaction = stretched->tick(request);
    info.t = stretched->time();
    try {
      monitor.on_tick(model, *stretched, info);
    } catch (const Error& e) {
      stopped_at = i;
      msg = e.what();
    }
  }
  // Positions read at tick 9; their pass runs over ticks 9 to 18.
  EXPECT_GE(stopped_at, 9) << msg;
  EXPECT_LE(stopped_at, 18) << msg;
  EXPECT_NE(msg.find("stretched by"), std::string::npos) << msg;
}

// A CPU backend that answers as the GL backend of organsim serve does: each
// tick returns the reaction of the tick before (latency 1), and
// reaction_positions() are that tick's end positions, kept without waiting.
// Counts what a monitor reads.
class LaggingBackend final : public test::ForwardingBackend {
 public:
  using ForwardingBackend::ForwardingBackend;
  mutable int positions_reads = 0, reaction_reads = 0;

  int32_t reaction_latency_ticks() const override { return 1; }
  Reaction tick(const TickRequest& request) override {
    inner_->positions(before_);  // the end of the tick before: the one this tick's reaction is of
    const Reaction now = inner_->tick(request);
    const Reaction out = last_;
    last_ = now;
    started_ = true;
    return out;
  }
  void positions(std::vector<Vec3>& out) const override {
    ++positions_reads;
    inner_->positions(out);
  }
  void reaction_positions(std::vector<Vec3>& out) const override {
    if (!started_) throw Error(ErrorKind::Backend, "reaction_positions() before the first tick");
    ++reaction_reads;
    out = before_;
  }

 private:
  std::vector<Vec3> before_;
  Reaction last_;
  bool started_ = false;
};

// organsim serve's monitor checks the reaction's tick's positions: it never
// reads the tick in flight (positions() only at the start, when nothing is
// in flight), stays quiet on a stable run, and still stops an unstable one
// with the energy finding, at most the latency later than on positions().
TEST(StabilityBlowup, OnTheReactionsPositionsItNeverWaitsForTheTickInFlightAndStillStopsABlowUp) {
  const Model sag = sagging_box();
  const StabilityReport rs = estimate_critical_step(sag);
  BlowupMonitorOptions options;
  options.interval_ticks = 10;
  options.reaction_positions = true;
  LaggingBackend quiet_backend(make_cpu_backend(sag, {}, testing::one_thread()));
  BlowupMonitor quiet(options, {0.9 * rs.dt_crit, 0, 0, rs});
  EXPECT_EQ(run_with_monitor(sag, quiet_backend, quiet, 0.9 * rs.dt_crit, 10, 200), "");
  EXPECT_EQ(quiet.checks(), 20);
  EXPECT_EQ(quiet_backend.positions_reads, 1);  // on_start
  EXPECT_EQ(quiet_backend.reaction_reads, 20);

  const Model model = testing::stability_box(3, 0.03, testing::undamped_material());
  const StabilityReport r = estimate_critical_step(model);
  std::vector<Vec3> x = model.rest_position;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) x[i] += 1e-9 * Vec3(std::sin(i), std::cos(3 * i), std::sin(7 * i));
  const double dt = 1.3 * r.dt_crit;
  const auto stop_time = [&](bool reaction_positions, std::string& msg) {
    LaggingBackend backend(make_cpu_backend(model, {}, testing::one_thread()));
    backend.set_state(x, x);
    BlowupMonitorOptions o;
    o.interval_ticks = 10;
    o.reaction_positions = reaction_positions;
    BlowupMonitor monitor(o, {dt, 0, 0, r});
    msg = run_with_monitor(model, backend, monitor, dt, 5, 2000);
    if (reaction_positions) {
      EXPECT_EQ(backend.positions_reads, 1);
    }
    return backend.time();
  };
  std::string direct, lagged;
  const double t_direct = stop_time(false, direct), t_lagged = stop_time(true, lagged);
  ASSERT_NE(direct, "");
  ASSERT_NE(lagged, "");
  EXPECT_NE(lagged.find("kinetic energy"), std::string::npos) << lagged;
  EXPECT_EQ(lagged.find("non-finite"), std::string::npos) << lagged;
  // The same checks on positions one tick older: found at the same check or the next one.
  EXPECT_GE(t_lagged, t_direct);
  EXPECT_LE(t_lagged, t_direct + 10.5 * 5 * dt) << direct << "\n" << lagged;
}

// Through the run loop: the stop leaves a valid forces.json that says the run
// was cut short and why, with the samples up to the stop.
TEST(StabilityBlowup, RunLoopWritesTruncatedLog) {
  namespace fs = std::filesystem;
  const Model model = testing::stability_box(3, 0.03, testing::undamped_material());
  const StabilityReport r = estimate_critical_step(model);
  Scenario s;
  s.file = "inline";
  s.time.dt = 1.5 * r.dt_crit;
  s.time.substeps = 5;
  s.time.duration = 400 * s.time.tick();
  auto backend = make_cpu_backend(model, {}, testing::one_thread());
  // The rest state is exactly force-free: seed the unstable mode.
  std::vector<Vec3> x = model.rest_position;
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) x[i] += 1e-9 * Vec3(std::sin(i), std::cos(3 * i), std::sin(7 * i));
  backend->set_state(x, x);
  BlowupMonitor monitor({}, {s.time.dt, 0, 0, r});
  RunOptions options;
  options.outdir = fs::path(ORGANSIM_TEST_TMP) / "stability_blowup_log";
  fs::remove_all(options.outdir);
  options.observers.push_back(&monitor);
  EXPECT_THROW(run_scenario(s, model, *backend, options), Error);
  std::ifstream in(options.outdir / "forces.json");
  ASSERT_TRUE(in.good());
  const nlohmann::json log = nlohmann::json::parse(in);
  EXPECT_FALSE(log["meta"]["completed"].get<bool>());
  const std::string reason = log["meta"]["stop_reason"].get<std::string>();
  EXPECT_NE(reason.find("run stopped at t = "), std::string::npos) << reason;
  const size_t n = log["samples"]["t"].size();
  EXPECT_GT(n, 0u);
  EXPECT_LT(n, 400u);
  for (const auto& f : log["samples"]["force"])
    for (const auto& c : f) EXPECT_TRUE(c.is_number());  // no null (NaN) in the output
}

}  // namespace
}  // namespace stability_blowup_test
}  // namespace organsim
