// `organsim serve SCENARIO.json [-o OUTDIR] [--port 18944] [--bind 127.0.0.1] ...`:
// the scenario's model stepped in real time, its tool driven by an
// OpenIGTLink client (docs/live.md). The run is the ordinary run loop
// (core/run) with a LiveSession (core/live) as its tool driver and an
// IgtlServer (igtl/) as the session's link; OUTDIR gets forces.json and
// session.json, which `organsim run` replays bit for bit.
#include <omp.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "app/backend_factory.h"
#include "app/command.h"
#include "app/progress_line.h"
#include "app/run_observers.h"
#include "app/scenario_mesh.h"
#include "app/stop_signals.h"
#include "core/live/live_session.h"
#include "core/live/session_scenario.h"
#include "core/run/integrator_report.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "igtl/igtl_server.h"

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct ServeArgs {
  std::string scenario;
  std::string outdir;
  std::string backend;
  std::string precision;
  int32_t threads = -1;
  int port = 18944;
  std::string bind = "127.0.0.1";
  std::string device;
  std::string client_units = "mm";
  std::string client_transform;
  double duration = 60;
  bool allow_unstable = false;
  double surface_rate = 0;
  int realtime_priority = 0;  // 0: the loop at the normal policy
};

// Writes OUTDIR/session.json; false (and nothing written) when no tick was served: there is nothing to replay.
bool write_session(const fs::path& path, const ServeArgs& args, const LiveSession& session, const Backend& backend) {
  if (session.ticks() == 0) return false;
  const nlohmann::json j = session_scenario(args.scenario, session.keyframes(), session.end_time(), backend.name(),
                                            backend.precision(), session.cuts(), session.scripted_applied());
  write_file_atomically(path, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
  return true;
}

// "All threads" (a scenario's backend.threads 0) means all but one in a
// live loop, unless --threads or OMP_NUM_THREADS says otherwise: the
// network, the client (often on the same machine) and the system need a
// core, and a stepping thread the OS deschedules stalls the whole tick
// (docs/live.md, "Threads"). The CPU backend takes the last one too while a
// step on the others takes over kLiveShare of dt (a slow machine, where
// every tick would be late), except with --realtime-priority, which needs
// the core free.
constexpr double kLiveShare = 0.8;
void leave_a_hardware_thread(int32_t asked, BackendSelection& selection, bool realtime) {
  if (asked >= 0 || selection.threads != 0 || std::getenv("OMP_NUM_THREADS")) return;
  const int procs = omp_get_num_procs();
  if (procs < 2) return;
  if (realtime) {
    omp_set_num_threads(procs - 1);
    std::cout << "threads:  at most " << procs - 1 << " of " << procs
              << " hardware threads, one left to the network and the client (--threads to change)\n";
    return;
  }
  selection.cpu_live_share = kLiveShare;
  std::cout << "threads:  cpu: " << procs - 1 << " of " << procs
            << " hardware threads, one left to the network and the client, all " << procs
            << " while a step takes over " << kLiveShare << " dt on " << procs - 1 << " (--threads to fix)\n";
}

// The loop thread at SCHED_FIFO `priority` (docs/live.md, "Threads"), so
// that no other thread of the machine's normal policy (the client, a
// build) takes its core mid-tick. Only with a hardware thread left to the
// others: real-time threads on every core would starve the network and
// the client, and the kernel throttles them for 50 ms a second. Set after
// the frame writer and OpenMP's pool exist (an empty parallel region makes
// the pool), so that they keep the normal policy; the change worker sets
// its own. `threads` is the backend's count (0: OpenMP's). Returns the
// policy as the system reports it, for the meta.
nlohmann::json raise_loop_priority(int priority, int32_t threads) {
  const int procs = omp_get_num_procs(), steppers = threads > 0 ? threads : omp_get_max_threads();
  if (steppers >= procs)
    throw Error(ErrorKind::Usage, "--realtime-priority: the loop's " + std::to_string(steppers) +
                                      " stepping threads would take all " + std::to_string(procs) +
                                      " hardware threads; leave one to the network and the client (--threads " +
                                      std::to_string(std::max(1, procs - 1)) + " or fewer)");
#pragma omp parallel num_threads(steppers)
  { /* makes OpenMP's pool at the normal policy */ }
  sched_param param{};
  param.sched_priority = priority;
  if (const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param); err != 0)
    throw Error(ErrorKind::Usage, "--realtime-priority " + std::to_string(priority) + ": the system refused SCHED_FIFO (" +
                                      std::strerror(err) + "); it needs CAP_SYS_NICE or a real-time priority limit "
                                      "(ulimit -r) of at least " + std::to_string(priority));
  int policy = 0;
  pthread_getschedparam(pthread_self(), &policy, &param);
  std::cout << "priority: the loop thread at " << (policy == SCHED_FIFO ? "SCHED_FIFO " : "policy ")
            << param.sched_priority << "\n";
  return {{"policy", policy == SCHED_FIFO ? "SCHED_FIFO" : std::to_string(policy)},
          {"priority", param.sched_priority}};
}

void serve_command(const ServeArgs& args) {
  Scenario s = load_scenario(args.scenario);
  if (!s.tool) throw Error(ErrorKind::Scenario, args.scenario + ": organsim serve needs a \"tool\": the client drives it");
  // A client sends the tool's position; its rotation is not applied, and the
  // reply's local stiffness is the frictionless sphere's.
  if (s.tool->spec.shape != ToolShape::Sphere)
    throw Error(ErrorKind::Scenario, args.scenario + ": organsim serve drives a sphere tool (tool.shape \"sphere\"); "
                                                     "a capsule's orientation and a grasper's jaws are not taken from the client");
  if (s.tool->spec.friction.on())
    throw Error(ErrorKind::Scenario, args.scenario + ": organsim serve's local stiffness has no friction term: "
                                                     "remove tool.friction");
  s.time.duration = args.duration;
  if (s.time.ticks() > 100'000'000) throw Error(ErrorKind::Usage, "--duration: more than 1e8 ticks");
  ClientFrame frame;
  frame.metres_per_unit = client_unit_metres(args.client_units);
  if (!args.client_transform.empty()) frame.to_scene = read_client_transform(args.client_transform);

  BackendSelection selection = scenario_backend_selection(s, args.backend, args.precision, args.threads);
  leave_a_hardware_thread(args.threads, selection, args.realtime_priority > 0);
  selection.gl_keep_reaction_positions = true;  // the reply's stiffness and the surface without waiting for the tick in flight
  const std::string backend_choice = resolve_auto_backend(selection);
  if (!backend_choice.empty()) std::cout << "backend:  " << backend_choice << "\n";
  s.backend.name = selection.name;
  const TetMesh mesh = load_scenario_mesh(s.mesh);
  const Model model = build_scenario_model(s, mesh);
  auto backend = make_backend(selection, model, backend_tool(s));
  const fs::path outdir = args.outdir.empty() ? fs::path("out") / (fs::path(args.scenario).stem().string() + "_live")
                                              : fs::path(args.outdir);
  auto observers = make_observers(s, model, outdir, nullptr);
  PrepareRunOptions prepare_options;
  prepare_options.threads = selection.threads;
  const PreparedRun prepared = prepare_run(s, model, prepare_options);
  const std::string step_warning = check_time_step(prepared.stability, s.time.dt, s.time.substeps, args.allow_unstable, s.time.integrator);
  if (!step_warning.empty()) std::cerr << "organsim: " << step_warning << "\n";
  // On the reaction's tick's positions (GL: kept on the GPU), so that a check never waits for the tick in flight.
  BlowupMonitor monitor = prepared.blowup_monitor(s, s.time.dt, backend->default_check_interval_ticks(), true);
  prepared.start(*backend);

  // Before the port opens: a refusal leaves nothing listening.
  const nlohmann::json loop_scheduling =
      args.realtime_priority > 0 ? raise_loop_priority(args.realtime_priority, selection.threads) : nlohmann::json();
  StopSignals signals;  // SIGINT ends the session after the current tick, with its record written
  // With surfaces each client's send buffer holds a liver surface (about
  // 130 KB) and its replies; without, a small one keeps replies fresh.
  IgtlServer server(args.bind, args.port, &std::cerr,
                    args.surface_rate > 0 ? 512 * 1024 : IgtlServer::kRepliesSendBuffer);
  LiveOptions live;
  live.frame = frame;
  live.device = args.device;
  live.scene = scene_box(model.rest_position);
  live.tick = s.time.tick();
  live.start = s.tool->spec.position_at(0);
  live.stop = &stop_requested();
  live.log = &std::cerr;
  live.surface_rate = args.surface_rate;
  for (const CutEvent& c : s.events.cuts) live.cut_names.push_back(c.name);
  // The scenario's cuts over one tick go to the run through the session, off the tick's path like a client's.
  live.scripted_cuts = take_one_tick_cuts(s.events, s.time.tick());
  live.tool = backend_tool(s);
  if (stderr_is_terminal()) live.status = [](const std::string& line) { std::cerr << "organsim " << line << "\n"; };
  LiveSession session(server, live);

  RunOptions options;
  options.outdir = outdir;
  options.allow_unstable = args.allow_unstable;
  options.observers.push_back(&monitor);  // first: nothing else sees a blown-up state
  for (auto& o : observers) options.observers.push_back(o.get());
  options.observers.push_back(&session);  // last: the reply leaves once the tick is checked
  options.tool_driver = &session;
  options.meta_extra = {{"mesh", s.mesh.path.string()}, {"command", "serve"}};
  if (!loop_scheduling.is_null()) options.meta_extra["loop_scheduling"] = loop_scheduling;
  options.meta_extra.update(prepared.meta());
  if (!backend_choice.empty()) options.meta_extra["backend_choice"] = backend_choice;

  std::cout << "model:    " << model.npoint() << " points, tick " << s.time.tick() << " s, at most " << s.time.ticks()
            << " ticks (--duration " << args.duration << " s) on " << backend->name() << " (" << backend->precision()
            << ", " << backend->device() << ")\n";
  std::cout << "serve:    OpenIGTLink on " << args.bind << ":" << server.port()
            << ", waiting for a client (TRANSFORM in " << args.client_units << "; replies SENSOR \"ToolReaction\")"
            << std::endl;
  const fs::path session_path = outdir / "session.json";
  RunResult result;
  try {
    result = run_scenario(s, model, *backend, options);
  } catch (const Error& e) {
    server.send_notice(e.what());
    write_session(session_path, args, session, *backend);
    std::cerr << "organsim: the record up to the failure is in " << outdir.string() << " (forces.json, session.json)\n";
    throw;
  }
  if (!write_session(session_path, args, session, *backend)) {
    std::cout << "done:     no tick served (stopped before a client connected); nothing to replay\n";
    return;
  }
  const nlohmann::json& l = result.meta.extra["live"];
  std::cout << "done:     " << session.ticks() << " ticks (" << session.end_time() << " s), " << l["late_ticks"]
            << " late, real-time factor " << std::setprecision(3) << l["real_time_factor"].get<double>()
            << (session.stopped_by().empty() ? "" : ", stopped by " + session.stopped_by()) << "\n";
  std::cout << "latency:  median " << l["latency"]["median_ms"].get<double>() << " ms, p99 "
            << l["latency"]["p99_ms"].get<double>() << " ms, max " << l["latency"]["max_ms"].get<double>() << " ms over "
            << l["latency"]["count"] << " poses (receipt to force reply)\n";
  std::cout << "traffic:  " << l["poses_received"] << " poses received, " << l["poses_applied"] << " applied, "
            << l["link"]["replies_sent"] << " replies sent, " << l["link"]["replies_dropped"] << " dropped\n";
  if (const std::string line = integrator_summary(result.meta.extra.value("integrator", nlohmann::json())); !line.empty())
    std::cout << "implicit: " << line << "\n";
  std::cout << "force log: " << result.forces_path.string() << "\n";
  std::cout << "session:  " << session_path.string() << " (organsim run " << session_path.string() << " replays it)\n";
  // As `organsim run`: the record is whole, the exit status says the solves fell short.
  if (const std::string warning = integrator_warning(*backend); !warning.empty())
    throw Error(ErrorKind::SolverWarning, warning);
}

const bool serve_registered = register_command("serve", 25, [](CLI::App& root) {
  auto args = std::make_shared<ServeArgs>();
  CLI::App* cmd = root.add_subcommand(
      "serve", "Step a scenario's model in real time with its tool driven over OpenIGTLink (TRANSFORM in, SENSOR "
               "force and torque out, every tick); record forces.json and a replayable session.json (docs/live.md).");
  cmd->add_option("scenario", args->scenario, "Scenario file with a tool (its keyframes give only the start)")->required();
  cmd->add_option("-o,--output", args->outdir, "Output folder (default: out/<scenario name>_live)");
  cmd->add_option("--port", args->port, "TCP port (default 18944, OpenIGTLink's; 0: any free port, printed)")
      ->check(CLI::Range(0, 65535));
  cmd->add_option("--bind", args->bind, "IPv4 address to listen on (default 127.0.0.1: this machine only)");
  cmd->add_option("--device", args->device,
                  "Device name of the tool's TRANSFORM (e.g. ToolToReference; default: the first that sends)");
  cmd->add_option("--client-units", args->client_units, "Length unit of the client's poses: mm (default) or m")
      ->check(CLI::IsMember({"mm", "m"}));
  cmd->add_option("--client-transform", args->client_transform,
                  "JSON file with a rigid 4x4 matrix from the client's frame to the scene's (translation in client "
                  "units; default identity)");
  cmd->add_option("--duration", args->duration, "Session length in simulated seconds (default 60; SIGINT ends it sooner)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--backend", args->backend, "auto, cpu or gl; overrides the scenario's backend")
      ->check(CLI::IsMember({"auto", "cpu", "gl"}));
  cmd->add_option("--precision", args->precision, "double or float; overrides the scenario's precision")
      ->check(CLI::IsMember({"double", "float"}));
  cmd->add_option("--threads", args->threads,
                  "CPU threads (0: all); overrides the scenario's backend.threads, whose 0 (all) serve takes as all "
                  "but one")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--surface-rate", args->surface_rate,
                  "Send the boundary surface as POLYDATA \"OrganSurface\" this many times per second, in the "
                  "client's frame and units (e.g. 30 for 3D Slicer; default 0: never)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--realtime-priority", args->realtime_priority,
                  "Run the loop thread at SCHED_FIFO priority 1-99 (needs CAP_SYS_NICE or ulimit -r; default 0: the "
                  "normal policy); refused when the stepping threads would take every hardware thread")
      ->check(CLI::Range(0, 99));
  cmd->add_flag("--allow-unstable", args->allow_unstable,
                "Serve even when time.dt exceeds the critical step dt_crit [s] (the blow-up check will likely stop it)");
  cmd->callback([args] { serve_command(*args); });
});

}  // namespace
}  // namespace organsim::app
