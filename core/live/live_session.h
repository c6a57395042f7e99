#pragma once
// `organsim serve`'s session, apart from the protocol: it paces the ordinary
// run loop (core/run, through ToolDriver) to the wall clock, applies each
// client pose at the tick it arrives in (the last pose holds in between and
// while no client is connected), turns a client's CUT command into a cut
// over the next tick (client_command.h), replies with every tick's reaction, keeps
// the timing figures, and records the tool path so that the session replays
// as an ordinary scenario (session_scenario.h).
//
// Tick i (simulated [t0, t1]) starts at wall time start + t0, or up to one
// tick earlier as soon as a new pose arrives: a client that sends at the tick
// rate then gets its force without waiting for the clock, and the simulation
// never runs more than one tick ahead of it. A tick is late when its reply
// leaves after start + t1.
#include <atomic>
#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/live/client_command.h"
#include "core/live/client_frame.h"
#include "core/live/live_link.h"
#include "core/live/refusal_log.h"
#include "core/model/contact_layer.h"
#include "core/run/tool_driver.h"
#include "core/scenario/events.h"
#include "core/scenario/tool_spec.h"
#include "core/sim/run_observer.h"
#include "core/sim/tool.h"

namespace organsim {

struct LiveOptions {
  ClientFrame frame;
  std::string device;        // the tool's device name; empty: whichever sends first
  SceneBox scene;            // poses outside are refused
  double tick = 1e-3;        // s, the scenario's dt * substeps
  Vec3 start{0, 0, 0};       // the tool centre until the first pose (the scenario's at t = 0), m
  const std::atomic<bool>* stop = nullptr;  // set (by SIGINT) to end the session after the current tick
  std::ostream* log = nullptr;              // refusals, connections
  // Called about every status_interval wall seconds with a one-line summary.
  std::function<void(const std::string&)> status;
  double status_interval = 2.0;  // s
  // The boundary surface to the clients this many times per wall second (0: never).
  double surface_rate = 0;  // Hz
  std::vector<std::string> cut_names;  // the scenario's cuts: a client's cut gets another name
  BackendTool tool;  // for the contact stiffness in each reply (push only)
  // The scenario's cuts that sweep over one tick (take_one_tick_cuts), with
  // their index among its cuts, by start time: each is handed to the run at
  // its tick as a client's cut is, so that it is built off the tick's path.
  std::vector<std::pair<size_t, CutEvent>> scripted_cuts;
  // The clock the session keeps its schedule on: the session's start, each
  // tick's start and the deadlines it hands the link, the wake-ups, late
  // ticks, reply latencies, slowest ticks and the status and surface
  // intervals. It must be the clock the link's deadlines and receipt times
  // are on. Empty: LiveClock::now, as IgtlServer (organsim serve). A test
  // passes its fake link's clock, which moves only when the fake link says
  // time passed, so that the timing rules are checked exactly, whatever
  // the machine's scheduling. (The reply stiffness's CPU time is measured
  // on LiveClock: it is work, not schedule.)
  std::function<LiveClock::time_point()> clock;
};

// Whether `cut` is active over exactly one tick [i tick, (i + 1) tick] of the
// run loop (two keyframes, neither applied_at nor when_ready): a cut that a
// live session can build off the tick's path. A sweep over several ticks
// cannot be: each tick's part starts from the Model the last one made.
bool sweeps_one_tick(const CutEvent& cut, double tick);

// Moves the cuts of `events` that sweep over one tick out of it, with their
// index among its cuts, for LiveOptions::scripted_cuts.
std::vector<std::pair<size_t, CutEvent>> take_one_tick_cuts(EventsDef& events, double tick);

// One applied pose, for the force log: the tick it was applied at, when it
// arrived (s after the session started), who sent it and the matrix as sent.
struct AppliedPose {
  int64_t tick = 0;
  double received = 0;
  ClientPose pose;
};

class LiveSession : public ToolDriver, public RunObserver, private LivePoseSink {
 public:
  LiveSession(LiveLink& link, LiveOptions options);

  // ToolDriver: waits for the first client (tick 0), then for the tick's time.
  std::optional<Vec3> tool_at_end_of(int64_t tick, double t_end) override;
  // The cut over the tick just asked for: a scripted one-tick cut due then,
  // or else the client's, if a CUT came before it; built off the tick's
  // path (when_ready).
  std::optional<CutEvent> cut_for_tick() override;
  // Records the tick that swapped the oldest cut in flight in (its applied_at in session.json).
  void cut_applied(double t0) override;
  void add_meta(nlohmann::json& extra) const override;
  // RunObserver: sends the tick's reaction and keeps the timing (and the surface now and then).
  void on_start(const Model& model, Backend& backend) override;
  void on_topology_changed(const Model& next, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;

  // The tool path as keyframes that reproduce every tick's tool centre
  // exactly with ToolSpec::position_at (a hold, then the step to the new
  // pose at the end of the tick that applied it).
  std::vector<Keyframe> keyframes() const { return {keyframes_.begin(), keyframes_.end()}; }
  // Simulated time at the end of the last tick served, s (0 before any).
  double end_time() const { return end_time_; }
  int64_t ticks() const { return ticks_; }
  const std::deque<AppliedPose>& applied() const { return applied_; }
  // The client's cuts as scripted cuts over the ticks that made them, with
  // the tick that swapped each in (applied_at; for a cut still being built
  // when the session ended, its end: never), for session.json.
  std::vector<CutEvent> cuts() const;
  // The scripted one-tick cuts handed to the run: their index among the
  // scenario's cuts and the tick that swapped each in (as cuts()), for
  // their applied_at in session.json.
  std::vector<std::pair<size_t, double>> scripted_applied() const;
  // Why the session ended early ("SIGINT"), empty otherwise.
  const std::string& stopped_by() const { return stopped_by_; }

 private:
  bool on_pose(const ClientPose& pose) override;
  void on_text(const ClientText& text) override;
  void make_cut(int64_t tick, double t_start, double t_end);
  void apply_pending(int64_t tick, double t_start, double t_end);
  void maybe_status(LiveClock::time_point now);
  // Waits for the link until `deadline` (or a pose that starts the tick)
  // and, when the wait ran out on the clock, records how late it woke.
  void wait_until(LiveClock::time_point deadline);
  // Keeps the slowest ticks (wall time from the last reply to this one).
  void note_tick_wall(int64_t tick, double seconds);
  void find_surface(const Model& model);
  // The surface at the end of the reaction's tick (time t), at most surface_rate times a second.
  void maybe_surface(Backend& backend, double t, LiveClock::time_point now);

  LiveLink& link_;
  LiveOptions o_;
  RefusalLog refusals_;          // poses
  RefusalLog command_refusals_;  // STRING commands
  std::string device_;  // the device followed (o_.device or the first sender)

  LiveClock::time_point start_{};
  LiveClock::time_point early_{};  // a new pose from here on starts the tick
  std::optional<ClientPose> pending_;  // the newest pose not yet applied
  // When a pose asked the link to return and start the tick (in this wait).
  std::optional<LiveClock::time_point> pose_started_at_;
  Vec3 pending_position_{0, 0, 0};
  int64_t superseded_ = 0;   // poses replaced by a newer one before a tick applied them
  int64_t poses_received_ = 0;

  Vec3 current_;
  std::optional<std::array<double, 16>> current_matrix_;  // the last applied pose, as sent
  // A CUT received and not yet made (with who sent it), the cut made for
  // this tick until the run takes it, and every cut made.
  std::optional<std::pair<CutCommand, ClientText>> cut_requested_;
  std::optional<CutEvent> cut_this_tick_;
  std::vector<CutEvent> cuts_;
  // The scripted cuts' swap-in times (o_.scripted_cuts' order) and the next one due.
  std::vector<std::optional<double>> scripted_applied_at_;
  size_t next_scripted_ = 0;
  // Cuts handed to the run and not yet swapped in, oldest first: (scripted,
  // index into o_.scripted_cuts or cuts_).
  std::deque<std::pair<bool, size_t>> in_flight_;
  nlohmann::json cut_log_ = nlohmann::json::array();
  // The session's records grow by a tick's entries at a time for as long as
  // it runs: a deque never moves what it holds, where a vector's doubling
  // would copy them all on some tick (8193, 16385, ...: a stall of
  // milliseconds at a few thousand poses, page faults on the new block
  // included).
  std::deque<Keyframe> keyframes_;
  std::deque<AppliedPose> applied_;
  std::optional<LiveClock::time_point> tick_pose_received_;  // of the pose this tick applied
  double end_time_ = 0;
  int64_t ticks_ = 0;
  int64_t late_ = 0;
  std::deque<double> latencies_;  // s, one per tick that applied a pose
  // s, one per tick in contact: the reply's stiffness (the reaction's
  // positions and the pass over the surface), CPU work before each reply.
  std::deque<double> stiffness_seconds_;
  // s, one per wait that ran out on the clock: how long after its deadline
  // the loop thread ran again. The machine's scheduling latency as the
  // session meets it (what cyclictest measures), apart from the tick's work.
  std::deque<double> wake_up_seconds_;
  std::string stopped_by_;

  LiveClock::time_point last_status_{};
  int64_t status_ticks_ = 0, status_late_ = 0;
  size_t status_latencies_ = 0;
  double wall_seconds_ = 0;  // start to the last reply

  // The boundary surface: its points (internal ids) and triangles over them.
  std::vector<int32_t> surface_points_;
  std::vector<Tri> surface_triangles_;
  std::vector<Vec3> positions_, surface_client_;
  std::vector<Vec3> stiffness_positions_;  // the tissue at the end of the reaction's tick (in contact)
  ContactLayer contact_layer_;             // the Model version's, with tool.hertz_layer (the reply's stiffness)
  // Time and tool centre at the ends of the last ticks, newest last: the
  // reaction a tick returns is reaction_latency_ticks() older (GL: 1).
  std::vector<std::pair<double, Vec3>> recent_ends_;
  LiveClock::time_point last_reply_{};
  std::vector<std::pair<int64_t, double>> slowest_;  // (tick, s), slowest first, at most 5
  LiveClock::time_point last_surface_{};
  int64_t surfaces_ = 0;
};

}  // namespace organsim
