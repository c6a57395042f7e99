// LiveSession without sockets: a scripted link hands poses to the ordinary
// run loop through the session; the session's keyframes must then replay the
// same ticks bit for bit, and refused poses must change nothing.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <array>
#include <map>
#include <set>
#include <thread>

#include "core/gl/gl_backend.h"
#include "core/live/live_session.h"
#include "core/live/session_scenario.h"
#include "core/mesh/tet_mesh.h"
#include "core/run/run.h"
#include "core/model/contact_layer.h"
#include "core/sim/contact_stiffness.h"
#include "core/sim/cpu_backend.h"

namespace organsim {
namespace live_session_test {
namespace {

namespace fs = std::filesystem;

// A link and its clock, scripted: the poses and commands of a tick arrive
// in the session's first wait of that tick, on a fake clock that moves only
// here. A wait that nothing ends runs out exactly at its deadline (as on an
// idle machine, less the scheduler's delay), a pose arrives at the time the
// clock shows, and a scripted slow client or late wake-up moves the clock
// on by its milliseconds. The session's timing figures then follow from the
// script alone, however loaded the machine is. Raises `stop` before tick
// `stop_at`.
class ScriptedLink : public LiveLink {
 public:
  std::map<int64_t, std::vector<ClientPose>> script;
  std::map<int64_t, std::vector<std::string>> texts;  // STRING commands, after the tick's poses
  std::map<int64_t, int> pause_ms;  // a slow client: the clock moves on this long before the tick's messages arrive
  // A loop that wakes late: the tick's first wait that starts ahead of its
  // deadline runs out this long after it (then the tick's messages
  // arrive, if not yet); counted in `overslept`.
  std::map<int64_t, int> oversleep_ms;
  int overslept = 0;
  // Waits that started ahead of their deadline and ended at or after it (ran
  // out, or a pose came after it): what the session counts as wake-ups.
  int ran_out = 0;
  // Real time for the change worker, which builds a cut off the tick's path
  // at nice 19 and is swapped in at the first tick after it is done: from
  // tick `await_change_from` on, until a change is in (`changed`, set by
  // the ChangeSeen observer that serve() adds), each tick's first wait
  // sleeps 1 ms, then twice as long as the tick before up to 1 s: a few
  // milliseconds on an idle machine, about a minute in all over the
  // cube's ticks when other work takes the cores. The fake clock does
  // not move meanwhile.
  int64_t await_change_from = -1;
  bool changed = false;
  // Each tick's step and reply take this long on the clock (it moves on when the reply is sent).
  int work_us = 0;
  std::vector<std::pair<double, Vec3>> replies;  // (t, force)
  std::vector<Eigen::Matrix3d> stiffness;         // per reply
  int64_t stop_at = -1;
  std::atomic<bool> stop{false};

  // The fake clock (LiveOptions::clock).
  LiveClock::time_point now() const { return now_; }

  bool wait_for_client(const std::atomic<bool>&) override { return true; }
  void receive_until(LiveClock::time_point deadline, LivePoseSink& sink) override {
    const int64_t tick = static_cast<int64_t>(replies.size());
    if (tick == stop_at) stop = true;
    const bool ahead = now_ < deadline;
    if (ahead && oversleep_ms.count(tick) && overslept_at_ < tick) {
      now_ = deadline + std::chrono::milliseconds(oversleep_ms[tick]);
      overslept_at_ = tick;
      ++overslept;
    }
    bool started = false;  // a pose asked the link to return: the tick starts
    if (delivered_ <= tick) {
      delivered_ = tick + 1;
      await_change(tick);
      if (pause_ms.count(tick)) now_ += std::chrono::milliseconds(pause_ms[tick]);
      for (ClientPose p : script[tick]) {
        p.received = now_;
        started = sink.on_pose(p) || started;
      }
      for (const std::string& t : texts[tick]) sink.on_text({"Command", t, "test", now_});
    }
    if (!started && now_ < deadline) now_ = deadline;  // nothing ended the wait: it runs out on time
    if (ahead && now_ >= deadline) ++ran_out;
  }
  void send_reaction(int64_t, double t, const Vec3& force, const Vec3&, const Eigen::Matrix3d& k) override {
    now_ += std::chrono::microseconds(work_us);
    replies.push_back({t, force});
    stiffness.push_back(k);
  }
  std::vector<std::pair<double, std::vector<Vec3>>> surfaces;  // (t, points in the client's frame)
  void send_surface(double t, const std::vector<Vec3>& points, const std::vector<Tri>&) override {
    surfaces.push_back({t, points});
  }
  void send_notice(const std::string&) override {}
  nlohmann::json report() const override { return nlohmann::json::object(); }

 private:
  void await_change(int64_t tick) {
    if (await_change_from < 0 || tick < await_change_from || changed) return;
    std::this_thread::sleep_for(await_step_);
    await_step_ = std::min<std::chrono::milliseconds>(2 * await_step_, std::chrono::seconds(1));
  }
  int64_t delivered_ = 0;
  int64_t overslept_at_ = -1;
  LiveClock::time_point now_{std::chrono::hours(1)};
  std::chrono::milliseconds await_step_{1};
};

// Tells the link when the run swapped a new Model version in.
struct ChangeSeen : RunObserver {
  ScriptedLink* link = nullptr;
  void on_tick(const Model&, Backend&, const TickInfo&) override {}
  void on_topology_changed(const Model&, Backend&) override { link->changed = true; }
};

ClientPose pose_mm(const std::string& device, double x, double y, double z) {
  ClientPose p;
  p.device = device;
  p.client = "test";
  p.matrix = {1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z, 0, 0, 0, 1};
  return p;
}

// A 4 cm soft cube fixed at its bottom, the tool starting 1 mm above its top.
Scenario cube() {
  Scenario s;
  s.file = "cube.json";
  s.material.young_modulus = 5000;
  s.material.volume_modulus = 10000;
  s.gravity = Vec3::Zero();
  FixedSelector bottom;
  bottom.kind = FixedSelector::Kind::Box;
  bottom.min = Vec3(-1, -1, -1);
  bottom.max = Vec3(1, 1, 1e-6);
  s.fixed = {bottom};
  s.time.duration = 0.08;
  s.time.dt = 2e-4;
  s.time.substeps = 5;
  ToolDef tool;
  tool.spec.radius = 0.01;
  tool.spec.contact_stiffness = 500;
  tool.spec.keyframes = {{0.0, Vec3(0.02, 0.02, 0.051)}};
  s.tool = tool;
  return s;
}

struct Served {
  RunResult result;
  std::vector<Keyframe> keyframes;
  std::vector<CutEvent> cuts;
  std::vector<std::pair<size_t, double>> scripted;  // LiveSession::scripted_applied
  double end_time = 0;
  nlohmann::json live;
};

// The contact stiffness at each tick's end, from the backend's positions as the session sees them.
struct StiffnessProbe : RunObserver {
  BackendTool tool;
  const ContactLayer* layer = nullptr;  // with tool.hertz_layer
  std::vector<Eigen::Matrix3d> k;
  std::vector<double> t;
  std::vector<std::vector<Vec3>> x;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override {
    x.emplace_back();
    backend.positions(x.back());
    t.push_back(info.t);
    k.push_back(tool_contact_stiffness(model, x.back(), tool, info.tool_center, layer));
  }
};

// `probe`, if given, watches the run beside the session; `on`, if given, is
// the backend (else the double CPU backend).
Served serve(const Scenario& s, const Model& model, ScriptedLink& link, RunObserver* probe = nullptr,
             Backend* on = nullptr, double surface_rate = 0) {
  std::unique_ptr<Backend> cpu;
  if (!on) cpu = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  Backend* backend = on ? on : cpu.get();
  LiveOptions o;
  o.tool = backend_tool(s);
  o.tick = s.time.tick();
  o.start = s.tool->spec.position_at(0);
  o.scene = scene_box(model.rest_position);
  o.stop = &link.stop;
  o.surface_rate = surface_rate;
  Scenario run = s;  // as organsim serve: the one-tick cuts go through the session
  o.scripted_cuts = take_one_tick_cuts(run.events, o.tick);
  o.clock = [&link] { return link.now(); };
  LiveSession session(link, o);
  ChangeSeen seen;
  seen.link = &link;
  RunOptions r;
  r.outdir = fs::path(ORGANSIM_TEST_TMP) / "live_session";
  r.observers = {&session, &seen};
  if (probe) r.observers.push_back(probe);
  r.tool_driver = &session;
  Served out;
  out.result = run_scenario(run, model, *backend, r);
  out.keyframes = session.keyframes();
  out.cuts = session.cuts();
  out.scripted = session.scripted_applied();
  out.end_time = session.end_time();
  out.live = out.result.meta.extra["live"];
  return out;
}

RunResult replay(Scenario s, const Model& model, const Served& served) {
  s.tool->spec.keyframes = served.keyframes;
  s.time.duration = served.end_time;
  s.events.cuts.insert(s.events.cuts.end(), served.cuts.begin(), served.cuts.end());
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  RunOptions r;
  r.outdir = fs::path(ORGANSIM_TEST_TMP) / "live_session_replay";
  return run_scenario(s, model, *backend, r);
}

void expect_same_samples(const ForceSamples& a, const ForceSamples& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.t[i], b.t[i]) << i;
    ASSERT_EQ(a.tool_position[i], b.tool_position[i]) << i;
    ASSERT_EQ(a.force[i], b.force[i]) << i;
    ASSERT_EQ(a.torque[i], b.torque[i]) << i;
    ASSERT_EQ(a.contacts[i], b.contacts[i]) << i;
  }
}

Model cube_model(const Scenario& s) {
  return build_model(make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.04, 0.04, 0.04), 4, 4, 4), s.material, model_options(s),
                     "cube");
}

// A replayed session needs the tool exactly at each keyframe at its time;
// a + 1 * (b - a) is not b for these two numbers.
TEST(LiveSession, KeyframesGiveTheirExactPositionAtTheirTime) {
  ToolSpec tool;
  const Vec3 a(0.00938595867742349, 0, 0), b(0.002834747652200631, 0, 0);
  ASSERT_NE((a + 1.0 * (b - a)).x(), b.x());
  tool.keyframes = {{0.0, a}, {0.001, b}, {0.002, a}};
  EXPECT_EQ(tool.position_at(0.001), b);
  EXPECT_EQ(tool.position_at(0.002), a);
  EXPECT_EQ(tool.position_at(0.0005).x(), a.x() + 0.5 * (b.x() - a.x()));
}

TEST(LiveSession, PosesApplyAtTheirTickHoldBetweenAndReplayBitForBit) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  // Irregular poses in mm pressing into the top (z = 40 mm): some ticks get
  // none (the pose holds), tick 30 gets two (the newer wins), tick 50
  // repeats the pose it holds.
  for (int64_t k = 3; k < 70; k += 1 + k % 3) link.script[k] = {pose_mm("Tool", 20 + 0.01 * k, 20, 51 - 0.2 * k)};
  link.script[30].push_back(pose_mm("Tool", 21.234567, 19.5, 44.5));
  link.script[50] = {pose_mm("Tool", 20.5, 20, 45)};
  link.script[51] = {pose_mm("Tool", 20.5, 20, 45)};
  StiffnessProbe probe;
  probe.tool = backend_tool(s);
  const Served served = serve(s, model, link, &probe);

  const ForceSamples& f = served.result.samples;
  ASSERT_EQ(f.size(), 80u);
  // Each reply carries the contact's stiffness at the tick's end (zero
  // without contact; in contact, pressing deeper pushes back harder).
  ASSERT_EQ(link.stiffness.size(), 80u);
  int in_contact = 0;
  for (size_t k = 0; k < 80; ++k) {
    ASSERT_EQ(link.stiffness[k], probe.k[k]) << "tick " << k;
    if (f.contacts[k] == 0) {
      ASSERT_EQ(link.stiffness[k], Eigen::Matrix3d::Zero()) << "tick " << k;
    } else {
      ++in_contact;
      ASSERT_LT(link.stiffness[k](2, 2), 0) << "tick " << k;
    }
  }
  EXPECT_GT(in_contact, 20);
  // The stiffness's CPU time is kept for every tick in contact.
  EXPECT_EQ(served.live["reply_stiffness"]["count"], in_contact);
  EXPECT_GT(served.live["reply_stiffness"]["max_ms"].get<double>(), 0.0);
  EXPECT_EQ(link.replies.size(), 80u);
  Vec3 held = s.tool->spec.position_at(0);
  for (int64_t k = 0; k < 80; ++k) {
    if (link.script.count(k) && !link.script[k].empty()) {
      const auto& m = link.script[k].back().matrix;
      held = 1e-3 * Vec3(m[3], m[7], m[11]);
    }
    EXPECT_EQ(f.tool_position[static_cast<size_t>(k)], held) << "tick " << k;
    EXPECT_EQ(link.replies[static_cast<size_t>(k)].second, f.force[static_cast<size_t>(k)]) << "tick " << k;
  }
  double peak = 0;
  for (const Vec3& v : f.force) peak = std::max(peak, v.norm());
  EXPECT_GT(peak, 0.01) << "the path should press into the cube";
  EXPECT_EQ(served.live["poses_superseded"], 1);
  EXPECT_EQ(served.live["ticks"], 80);

  expect_same_samples(replay(s, model, served).samples, f);
}

// With the sub-cell Hertz layer the reply carries the layered contact's
// stiffness (softer along the push than the contact without it while the
// layer's offset still rises, its Hertz radius below R / 2: here pressed
// about 4 mm into the top at most), and the session replays bit for bit.
TEST(LiveSession, WithTheHertzLayerTheReplyCarriesTheLayeredStiffnessAndReplays) {
  Scenario s = cube();
  s.tool->spec.hertz_layer = true;
  const Model model = cube_model(s);
  ScriptedLink link;
  for (int64_t k = 3; k < 70; k += 2) link.script[k] = {pose_mm("Tool", 20.3, 19.7, 51 - 0.07 * k)};
  const ContactLayer layer = contact_layer(model);
  StiffnessProbe probe, plain;
  probe.tool = backend_tool(s);
  probe.layer = &layer;
  plain.tool = backend_tool(s);
  plain.tool.hertz_layer = false;
  ASSERT_TRUE(probe.tool.hertz_layer);
  const Served served = serve(s, model, link, &probe);
  const ForceSamples& f = served.result.samples;
  ASSERT_EQ(link.stiffness.size(), f.size());
  int in_contact = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    ASSERT_EQ(link.stiffness[k], probe.k[k]) << "tick " << k;
    if (f.contacts[k] == 0) continue;
    ++in_contact;
    const Eigen::Matrix3d without =
        tool_contact_stiffness(model, probe.x[k], plain.tool, f.tool_position[k]);
    EXPECT_LT(link.stiffness[k](2, 2), 0) << "tick " << k;
    EXPECT_GT(link.stiffness[k](2, 2), 0.95 * without(2, 2)) << "tick " << k;
  }
  EXPECT_GT(in_contact, 10);
  expect_same_samples(replay(s, model, served).samples, f);
}

// On the GL backend a tick returns the reaction of the tick before
// (reaction_latency_ticks 1), and the reply's stiffness is of that tick too:
// the contact at its end positions (kept on the GPU, so the reply never
// waits for the tick in flight) about its tool centre. So is the surface
// sent for display (here at every tick), with that tick's time.
TEST(LiveSession, OnTheGlBackendTheRepliesStiffnessAndSurfaceAreThoseOfTheReactionsTick) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  for (int64_t k = 3; k < 70; k += 2) link.script[k] = {pose_mm("Tool", 20, 20, 51 - 0.2 * k)};
  StiffnessProbe probe;
  probe.tool = backend_tool(s);
  GlBackendOptions keep;
  keep.keep_reaction_positions = true;
  GlBackend gl(model, backend_tool(s), keep);
  link.work_us = 100;  // no two replies at the same time on the clock: a surface after each
  const Served served = serve(s, model, link, &probe, &gl, 1e9);
  const ForceSamples& f = served.result.samples;
  ASSERT_EQ(link.stiffness.size(), 80u);
  int in_contact = 0;
  for (size_t k = 1; k < 80; ++k) {
    if (f.contacts[k] == 0) {
      ASSERT_EQ(link.stiffness[k], Eigen::Matrix3d::Zero()) << "tick " << k;
    } else {
      ++in_contact;
      ASSERT_EQ(link.stiffness[k], probe.k[k - 1]) << "tick " << k;
      ASSERT_LT(link.stiffness[k](2, 2), 0) << "tick " << k;
    }
  }
  EXPECT_GT(in_contact, 20);
  // Every tick from the second on sends the surface at the previous tick's
  // end: each point is one of that tick's positions, in the client's frame.
  ASSERT_EQ(link.surfaces.size(), 79u);
  const ClientFrame frame;
  for (size_t k = 1; k < 80; ++k) {
    const auto& [t, points] = link.surfaces[k - 1];
    ASSERT_EQ(t, probe.t[k - 1]) << "tick " << k;
    std::set<std::array<double, 3>> then;
    for (const Vec3& p : probe.x[k - 1]) {
      const Vec3 c = frame.client_position(p);
      then.insert({c.x(), c.y(), c.z()});
    }
    for (const Vec3& c : points) ASSERT_TRUE(then.count({c.x(), c.y(), c.z()})) << "tick " << k << ": " << c.transpose();
  }
}

// The session's deadlines are its start plus a tick's simulated time, cast
// to the clock's nanoseconds (truncated): a figure the clock gives exactly
// may be off by a nanosecond or two.
constexpr double kClockRoundingMs = 1e-5;

// meta.live.slowest_ticks names the ticks that took longest between two
// replies, slowest first: here the two a slow client held up (30 and 60 ms
// on the clock), then ticks paced by the clock (one tick, 1 ms, after the
// reply before); a tick behind the clock runs at once (0 ms).
TEST(LiveSession, TheSlowestTicksAreNamedWithTheirWallTime) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  link.pause_ms[7] = 30;
  link.pause_ms[15] = 60;
  const Served served = serve(s, model, link);
  const nlohmann::json& slowest = served.live["slowest_ticks"];
  ASSERT_EQ(slowest.size(), 5u) << slowest;
  for (size_t i = 1; i < slowest.size(); ++i) EXPECT_GE(slowest[i - 1]["ms"].get<double>(), slowest[i]["ms"].get<double>());
  EXPECT_EQ(slowest[0]["tick"], 15) << slowest;
  EXPECT_NEAR(slowest[0]["ms"].get<double>(), 60.0, kClockRoundingMs) << slowest;
  EXPECT_EQ(slowest[1]["tick"], 7) << slowest;
  EXPECT_NEAR(slowest[1]["ms"].get<double>(), 30.0, kClockRoundingMs) << slowest;
  for (size_t i = 2; i < 5; ++i) {
    // Ticks 1 to 6, before the first pause; after it the session is behind the clock to the end.
    EXPECT_GE(slowest[i]["tick"].get<int64_t>(), 1) << slowest;
    EXPECT_LE(slowest[i]["tick"].get<int64_t>(), 6) << slowest;
    EXPECT_NEAR(slowest[i]["ms"].get<double>(), 1.0, kClockRoundingMs) << slowest;
  }
}

// meta.live.wake_up counts the waits that ran out on the clock and how late
// the loop ran after each: every wait the session began ahead of its
// deadline and that nothing ended before it, on time (0 ms) but for the two
// the link overslept, 3 ms at tick 10 and 6 ms at tick 40, where the pose
// came after the late wake-up (read in the link's last pass); the session's
// other waits were behind the clock or ended by a pose (no wake-up).
TEST(LiveSession, ItsWakeUpsFromTheClockAreCountedWithHowLateTheyCame) {
  Scenario s = cube();
  s.time.duration = 0.06;
  const Model model = cube_model(s);
  ScriptedLink link;
  link.oversleep_ms[10] = 3;
  link.oversleep_ms[40] = 6;
  // Tick 39 starts a tick early at its pose, so that tick 40's first wait is ahead of its deadline.
  link.script[39] = {pose_mm("Tool", 20, 20, 50.5)};
  link.script[40] = {pose_mm("Tool", 20, 20, 50)};
  const Served served = serve(s, model, link);
  const nlohmann::json& wake = served.live["wake_up"];
  EXPECT_EQ(link.overslept, 2);
  EXPECT_GT(link.ran_out, 20) << "the ticks paced by the clock wait for it";
  EXPECT_EQ(wake["count"].get<int64_t>(), link.ran_out) << wake;
  EXPECT_EQ(wake["over_1_ms"].get<int64_t>(), 2) << wake;
  EXPECT_EQ(wake["over_0.25_ms"].get<int64_t>(), 2) << wake;
  EXPECT_NEAR(wake["max_ms"].get<double>(), 6.0, kClockRoundingMs) << wake;
  EXPECT_NEAR(wake["median_ms"].get<double>(), 0.0, kClockRoundingMs) << wake;
  // Tick 40 applied its pose: it started at the pose that came after the late wake-up.
  EXPECT_EQ(served.result.samples.tool_position[40], Vec3(0.02, 0.02, 0.05));
}

// Where the session's first applied pose lives, after every tick.
struct RecordAddressProbe : RunObserver {
  const LiveSession* session = nullptr;
  std::set<const AppliedPose*> first;
  size_t applied = 0;
  void on_tick(const Model&, Backend&, const TickInfo&) override {
    applied = session->applied().size();
    if (applied > 0) first.insert(&session->applied().front());
  }
};

// The records grow by a tick at a time and are never moved (a vector's
// doubling would copy them all on one tick: a stall of milliseconds a few
// thousand poses into a session), so the first applied pose stays where it
// was first recorded while a pose arrives every tick.
TEST(LiveSession, ItsRecordsGrowWithoutMovingWhatTheyHold) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  for (int64_t k = 0; k < 80; ++k) link.script[k] = {pose_mm("Tool", 20, 20, 51 - 0.01 * k)};
  auto backend = make_cpu_backend(model, backend_tool(s), {Precision::Double, 1});
  LiveOptions o;
  o.tool = backend_tool(s);
  o.tick = s.time.tick();
  o.start = s.tool->spec.position_at(0);
  o.scene = scene_box(model.rest_position);
  o.clock = [&link] { return link.now(); };
  LiveSession session(link, o);
  RecordAddressProbe probe;
  probe.session = &session;
  RunOptions r;
  r.outdir = fs::path(ORGANSIM_TEST_TMP) / "live_session_records";
  r.observers = {&session, &probe};
  r.tool_driver = &session;
  run_scenario(s, model, *backend, r);
  EXPECT_EQ(probe.applied, 80u);
  EXPECT_EQ(probe.first.size(), 1u) << "the first applied pose was moved " << probe.first.size() - 1 << " times";
}

// What the run loop hands each observer as a pulling tool's stiffness.
struct HeldStiffnessProbe : RunObserver {
  std::vector<Eigen::Matrix3d> k;
  void on_tick(const Model&, Backend&, const TickInfo& info) override { k.push_back(info.held_stiffness); }
};

// A pulling tool's reply carries its attachment springs' stiffness
// (-k sum s_i I) from the grasp to the release, and zero outside.
TEST(LiveSession, APullingToolsReplyCarriesItsAttachmentsStiffnessWhileItHolds) {
  Scenario s = cube();
  s.tool->spec.mode = ToolMode::Pull;
  s.tool->spec.keyframes = {{0.0, Vec3(0.02, 0.02, 0.04)}};  // on the top face
  s.tool->spec.grasp_radius = 0.012;
  s.tool->spec.grasp_time = 0.02;
  s.tool->spec.release_time = 0.05;
  const Model model = cube_model(s);
  ScriptedLink link;
  link.script[30] = {pose_mm("Tool", 20, 20, 45)};  // lift 5 mm while holding
  HeldStiffnessProbe probe;
  const Served served = serve(s, model, link, &probe);
  const RunResult& result = served.result;

  ASSERT_GT(result.grasped_points, 0);
  ASSERT_EQ(link.stiffness.size(), probe.k.size());
  const double k = s.tool->spec.contact_stiffness;
  for (size_t tick = 0; tick < link.stiffness.size(); ++tick) {
    const Eigen::Matrix3d& got = link.stiffness[tick];
    EXPECT_EQ(got, probe.k[tick]) << "tick " << tick;  // the client's frame is the scene's here
    const bool holding = tick >= 20 && tick < 50;
    if (!holding) {
      EXPECT_EQ(got, Eigen::Matrix3d::Zero()) << "tick " << tick;
      continue;
    }
    // Each held point adds -k s_i, s_i in (0, 1] (Model::tool_k_scale).
    EXPECT_TRUE(got.isApprox(got(0, 0) * Eigen::Matrix3d::Identity())) << "tick " << tick;
    EXPECT_LT(got(0, 0), -0.1 * k * result.grasped_points) << "tick " << tick;
    EXPECT_GE(got(0, 0), -k * result.grasped_points) << "tick " << tick;
  }
}

TEST(LiveSession, RefusedPosesChangeNothingAndAStopEndsTheRunWithAReplayableRecord) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  link.script[2] = {pose_mm("Tool", 20, 20, 48)};
  link.script[5] = {pose_mm("Tool", 20, nan, 48)};           // not finite
  link.script[6] = {pose_mm("Tool", 20, 20, 48000)};         // 48 m: metres sent as mm
  link.script[7] = {pose_mm("Other", 20, 20, 44)};           // not the followed device
  link.script[9] = {pose_mm("Tool", 20, 20, 46)};
  link.stop_at = 40;
  const Served served = serve(s, model, link);

  const ForceSamples& f = served.result.samples;
  EXPECT_EQ(f.size(), 40u) << "the stop ends the run before tick 40";
  EXPECT_TRUE(served.result.meta.completed);
  EXPECT_EQ(served.live["stopped_by"], "SIGINT");
  EXPECT_EQ(served.live["poses_refused"], (nlohmann::json{{"not_finite", 1}, {"other_device", 1}, {"outside_scene", 1}}));
  for (size_t k = 2; k < 9; ++k) EXPECT_EQ(f.tool_position[k], Vec3(0.02, 0.02, 0.048)) << k;
  EXPECT_EQ(f.tool_position[9], Vec3(0.02, 0.02, 0.046));
  EXPECT_EQ(served.end_time, f.t.back());
  expect_same_samples(replay(s, model, served).samples, f);
}

// A pose in mm whose z axis (the instrument's) points down into the cube and x axis along x.
ClientPose pose_down_mm(double x, double y, double z) {
  ClientPose p = pose_mm("Tool", x, y, z);
  p.matrix[5] = p.matrix[10] = -1;
  return p;
}

TEST(LiveSession, AClientCutIsBuiltOffTheTicksPathAndReplaysBitForBit) {
  const Scenario s = cube();
  const Model model = cube_model(s);
  ScriptedLink link;
  link.texts[1] = {"CUT"};                           // before any pose: refused
  link.script[2] = {pose_down_mm(20, 21, 46)};       // 4 mm into the top
  link.texts[4] = {"SLICE", "CUT 5", "cut -1 3"};    // not commands: refused
  link.texts[10] = {" cut ", "CUT"};                 // the second while the first is not in: refused
  link.script[20] = {pose_down_mm(22, 25, 46)};
  // The session does not wait for the worker (a change not in by the last
  // tick never is), and the fake clock does not either: the link gives the
  // worker real time from tick 11 until the change is in, up to a minute.
  link.await_change_from = 11;
  const Served served = serve(s, model, link);
  ASSERT_TRUE(link.changed) << "the cut was not in the model by the last tick";

  EXPECT_EQ(served.live["commands_refused"],
            (nlohmann::json{{"cut_busy", 1}, {"cut_without_pose", 1}, {"unknown_command", 3}}));
  ASSERT_EQ(served.cuts.size(), 1u);
  // The default blade: 20 mm from the tool centre down its z axis, swept 20 mm along its x axis over tick 10.
  const CutEvent& cut = served.cuts[0];
  EXPECT_EQ(cut.name, "client_cut1");
  ASSERT_EQ(cut.keyframes.size(), 2u);
  EXPECT_EQ(cut.keyframes[0].t, 10 * s.time.tick());
  EXPECT_EQ(cut.keyframes[1].t, 11 * s.time.tick());
  const double tol = 1e-15;  // mm to m and the blade's sums round in the last bit
  EXPECT_LT((cut.keyframes[0].a - Vec3(0.010, 0.021, 0.046)).norm(), tol);
  EXPECT_LT((cut.keyframes[0].b - Vec3(0.010, 0.021, 0.026)).norm(), tol);
  EXPECT_LT((cut.keyframes[1].a - Vec3(0.030, 0.021, 0.046)).norm(), tol);
  EXPECT_LT((cut.keyframes[1].b - Vec3(0.030, 0.021, 0.026)).norm(), tol);

  // Made from tick 10's positions on the worker and swapped in at a later
  // tick (whichever followed the worker's end): recorded as applied_at.
  const nlohmann::json& events = served.result.meta.extra["events"];
  ASSERT_EQ(events.size(), 1u) << events;
  EXPECT_EQ(events[0]["t"], 10 * s.time.tick());
  EXPECT_EQ(events[0]["sources"][0]["name"], "client_cut1");
  EXPECT_GT(events[0]["faces_separated"].get<int>(), 0);
  EXPECT_GT(events[0]["points_added"].get<int>(), 0);
  ASSERT_TRUE(cut.applied_at);
  EXPECT_GE(*cut.applied_at, 11 * s.time.tick());
  EXPECT_EQ(events[0]["applied_t"], *cut.applied_at);
  // The backend's tables were prepared on the worker as well; the tick only adopted them.
  EXPECT_TRUE(events[0].contains("backend_prepare_ms")) << events[0];
  EXPECT_EQ(served.live["cuts"][0]["applied_tick"], std::llround(*cut.applied_at / s.time.tick()));
  EXPECT_GT(served.result.meta.extra["final_points"].get<int>(), model.npoint());

  const RunResult again = replay(s, model, served);
  expect_same_samples(again.samples, served.result.samples);
  EXPECT_EQ(again.meta.extra["events"][0]["applied_t"], *cut.applied_at);
  EXPECT_EQ(again.meta.extra["final_points"], served.result.meta.extra["final_points"]);
}

// A cut goes off the tick's path only when it is active over one tick of the run loop.
TEST(LiveSession, OnlyACutOverOneTickOfTheRunLoopIsTakenOffTheTicksPath) {
  const double tick = 1e-3;
  const auto cut = [&](double from, double to) {
    CutEvent c;
    c.keyframes = {{from * tick, Vec3(0, 0, 0), Vec3(0, 0, 1)}, {to * tick, Vec3(1, 0, 0), Vec3(1, 0, 1)}};
    return c;
  };
  EXPECT_TRUE(sweeps_one_tick(cut(10, 11), tick));
  EXPECT_TRUE(sweeps_one_tick(cut(10, 10.5), tick));
  EXPECT_TRUE(sweeps_one_tick(cut(0, 1), tick));
  EXPECT_FALSE(sweeps_one_tick(cut(10.5, 11.5), tick));  // across two ticks
  EXPECT_FALSE(sweeps_one_tick(cut(10, 12), tick));
  CutEvent replayed = cut(10, 11);
  replayed.applied_at = 12 * tick;  // a recorded one goes in at its time
  EXPECT_FALSE(sweeps_one_tick(replayed, tick));
  CutEvent bent = cut(10, 11);
  bent.keyframes.insert(bent.keyframes.begin() + 1, {10.5 * tick, Vec3(0.5, 0, 0), Vec3(0.5, 0, 1)});
  EXPECT_FALSE(sweeps_one_tick(bent, tick));

  EventsDef events;
  events.cuts = {cut(20, 25), cut(30, 31), cut(10, 11)};
  const auto taken = take_one_tick_cuts(events, tick);
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].first, 2u);  // by start time, with their index among the scenario's cuts
  EXPECT_EQ(taken[1].first, 1u);
  ASSERT_EQ(events.cuts.size(), 1u);
  EXPECT_EQ(events.cuts[0].start(), 20 * tick);
}

// A scenario's cut over one tick is built on the worker like a client's,
// swapped in at a later tick, and replays bit for bit with that tick as its
// applied_at; session.json gives it that applied_at in place.
TEST(LiveSession, AScenariosOneTickCutIsBuiltOffTheTicksPathAndReplaysBitForBit) {
  Scenario s = cube();
  CutEvent slit;
  slit.name = "slit";
  slit.keyframes = {{10 * s.time.tick(), Vec3(0.010, 0.021, 0.046), Vec3(0.010, 0.021, 0.026)},
                    {11 * s.time.tick(), Vec3(0.030, 0.021, 0.046), Vec3(0.030, 0.021, 0.026)}};
  s.events.cuts = {slit};
  const Model model = cube_model(s);
  ScriptedLink link;
  link.script[2] = {pose_down_mm(20, 21, 46)};
  link.await_change_from = 11;  // real time for the worker (as above)
  const Served served = serve(s, model, link);
  ASSERT_TRUE(link.changed) << "the cut was not in the model by the last tick";

  ASSERT_EQ(served.scripted.size(), 1u);
  EXPECT_EQ(served.scripted[0].first, 0u);
  const double applied_at = served.scripted[0].second;
  EXPECT_GE(applied_at, 11 * s.time.tick());
  const nlohmann::json& events = served.result.meta.extra["events"];
  ASSERT_EQ(events.size(), 1u) << events;
  EXPECT_EQ(events[0]["t"], 10 * s.time.tick());
  EXPECT_EQ(events[0]["sources"][0]["name"], "slit");
  EXPECT_GT(events[0]["faces_separated"].get<int>(), 0);
  EXPECT_EQ(events[0]["applied_t"], applied_at);
  EXPECT_TRUE(events[0].contains("backend_prepare_ms")) << events[0];  // prepared on the worker
  EXPECT_TRUE(served.cuts.empty());

  Scenario again = s;
  again.events.cuts[0].applied_at = applied_at;
  const RunResult replayed = replay(again, model, served);
  expect_same_samples(replayed.samples, served.result.samples);
  EXPECT_EQ(replayed.meta.extra["events"][0]["applied_t"], applied_at);

  // session.json: the n-th cut among the scenario's events gets the applied_at, nothing is added.
  const fs::path file = fs::path(ORGANSIM_TEST_TMP) / "scripted_cut_scenario.json";
  {
    std::ofstream out(file);
    out << R"({"events": [{"suture": {"t": 1, "pairs": [[0, 1]], "stiffness": 10}},
                          {"cut": {"keyframes": []}}, {"cut": {"name": "slit", "keyframes": []}}]})";
  }
  const nlohmann::json j = session_scenario(file, served.keyframes, served.end_time, "cpu", "double", {}, {{1, applied_at}});
  ASSERT_EQ(j["events"].size(), 3u);
  EXPECT_FALSE(j["events"][1]["cut"].contains("applied_at"));
  EXPECT_EQ(j["events"][2]["cut"]["applied_at"], applied_at);
}

}  // namespace
}  // namespace live_session_test
}  // namespace organsim
