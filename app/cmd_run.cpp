// `organsim run SCENARIO.json [-o OUTDIR] [--backend cpu|gl] [--plan]`
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/backend_factory.h"
#include "app/command.h"
#include "app/progress_line.h"
#include "app/run_observers.h"
#include "app/scenario_mesh.h"
#include "core/model/material_summary.h"
#include "core/model/stiffness.h"
#include "core/run/integrator_report.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/util/error.h"

namespace organsim::app {

std::vector<RunObserverRegistration>& run_observer_registry() {
  static std::vector<RunObserverRegistration> registry;
  return registry;
}

std::vector<std::unique_ptr<RunObserver>> make_observers(const Scenario& s, const Model& model,
                                                         const std::filesystem::path& outdir, std::vector<std::string>* names) {
  std::vector<std::unique_ptr<RunObserver>> out;
  bool frames_produced = false;
  for (const auto& r : run_observer_registry()) {
    auto o = r.make(RunObserverContext{s, model, outdir});
    if (!o) continue;
    if (r.produces == "frames") frames_produced = true;
    if (names) names->push_back(r.name);
    out.push_back(std::move(o));
  }
  if (s.outputs.wants_rendering() && !frames_produced) {
    throw Error(ErrorKind::Scenario, s.file.string() + ": outputs.frames: frame rendering is not available in this build");
  }
  return out;
}

namespace {

namespace fs = std::filesystem;

struct RunArgs {
  std::string scenario;
  std::string outdir;
  std::string backend;
  std::string precision;
  int32_t threads = -1;
  bool plan = false;
  bool allow_unstable = false;   // run even when dt > dt_crit
  int32_t check_interval = 0;    // blow-up check every N ticks; 0: the backend's default
};

std::string human_bytes(size_t bytes) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1);
  if (bytes >= (1u << 20)) {
    s << bytes / double(1u << 20) << " MiB";
  } else if (bytes >= (1u << 10)) {
    s << bytes / double(1u << 10) << " KiB";
  } else {
    s << bytes << " B";
  }
  return s.str();
}


// "density 1000 kg/m^3, rule poisson_ratio, E 3000 Pa, nu 0.45 (springs E_s ...)".
std::string describe_material(const Material& material) {
  const nlohmann::json e = elasticity_json(material);
  std::ostringstream out;
  out << "density " << material.density << " kg/m^3, rule " << e["rule"].get<std::string>();
  if (e.contains("young_modulus")) {
    out << ", E " << e["young_modulus"].get<double>() << " Pa, nu " << e["poisson_ratio"].get<double>()
        << " (springs E_s " << e["spring_modulus"].get<double>() << " Pa, volume term "
        << e["volume_term_modulus"].get<double>() << " Pa, shear element " << e["shear_element_modulus"].get<double>()
        << " Pa)";
  } else {
    out << ", " << e["spring_stiffness"].get<double>() << " N/m per spring";
  }
  return out.str();
}

void print_plan(std::ostream& out, const Scenario& s, const Model& model, const Backend& backend,
                const std::vector<std::string>& observers) {
  const Plan plan = backend.plan();
  int32_t nfixed = 0;
  for (uint8_t f : model.fixed) nfixed += f;
  out << "model:    " << model.npoint() << " points (" << nfixed << " fixed), " << model.nspring()
      << " springs, " << model.ntet() << " tets, mass " << model.total_mass() << " kg, volume "
      << model.rest_volume() << " m^3\n";
  // What each material is, as the stiffness rules read it
  // (core/model/stiffness.h): one line, or one per label's material.
  if (model.materials.empty()) {
    out << "material: " << describe_material(model.material) << "\n";
  } else {
    out << "materials per label:\n";
    for (const MaterialUse& u : material_uses(model)) {
      out << "  - label";
      for (size_t i = 0; i < u.labels.size(); ++i) out << (i ? ", " : " ") << u.labels[i];
      out << ": " << describe_material(*u.material) << "\n";
    }
  }
  out << "time:     dt " << s.time.dt << " s x " << s.time.substeps << " substeps = tick " << s.time.tick()
      << " s, " << s.time.ticks() << " ticks (" << s.time.duration << " s)\n";
  out << "backend:  " << backend.name() << " (" << backend.precision() << ", " << backend.device()
      << "), reaction latency " << backend.reaction_latency_ticks() << " ticks\n";
  out << "passes per step:\n";
  for (const PassInfo& p : plan.passes) out << "  - " << p.name << ": " << p.detail << "\n";
  if (!plan.per_tick.empty()) {
    out << "once per tick:\n";
    for (const PassInfo& p : plan.per_tick) out << "  - " << p.name << ": " << p.detail << "\n";
  }
  if (s.events.any()) {
    out << "between ticks:\n  - topology: " << s.events.cuts.size() << " cut" << (s.events.cuts.size() == 1 ? "" : "s");
    if (s.events.tear) out << ", tear past strain " << s.events.tear->strain;
    out << " (faces separated, points split, backend rebuilt, dt_crit checked; see docs/topology.md)\n";
    for (const SutureEvent& u : s.events.sutures) {
      out << "  - sutures at t = " << u.t << " s: "
          << (u.along.empty() ? std::to_string(u.pairs.size()) + " given pairs" : "along cut \"" + u.along + "\"")
          << ", " << u.stiffness << " N/m each, tightening " << u.rate << " m/s to " << u.min_length
          << " m (springs added to the Model, tension only, on every CPU kernel and step.comp; the "
             "backend refreshes their rest lengths per tick; dt_crit checked)\n";
    }
  }
  out << "left out of this scene:\n";
  int32_t left_out = 0;
  auto note = [&](bool absent, const std::string& text) {
    if (!absent) return;
    out << "  - " << text << "\n";
    ++left_out;
  };
  note(!model.has_volume(), "no volume pass (material.volume_modulus = 0)");
  note(!s.tool, "no tool pass (no tool in the scenario)");
  note(!model.has_gravity(), "no gravity pass (gravity = [0, 0, 0])");
  note(!s.outputs.wants_rendering(), "no renderer (no outputs.frames)");
  note(!s.events.any(), "no topology pass (no events in the scenario)");
  if (left_out == 0) out << "  (nothing)\n";
  out << "buffers:\n";
  size_t total = 0;
  for (const BufferInfo& b : plan.buffers) {
    out << "  - " << b.name << ": " << human_bytes(b.bytes) << "\n";
    total += b.bytes;
  }
  out << "  total: " << human_bytes(total) << "\n";
  out << "dispatches per step: " << plan.dispatches_per_step << ", CPU-GPU synchronisations per step: "
      << plan.syncs_per_step << "\n";
  out << "outputs:  " << (s.outputs.forces ? "forces.json" : "(no force log)");
  for (const std::string& o : observers) out << ", " << o;
  out << "\n";
}

// Lists what the run wrote, so a user sees the frames, video and contact
// sheet next to the force log without looking.
void print_output_files(std::ostream& out, const fs::path& outdir) {
  std::vector<fs::directory_entry> entries;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(outdir, ec)) entries.push_back(e);
  std::sort(entries.begin(), entries.end(),
            [](const auto& a, const auto& b) { return a.path().filename() < b.path().filename(); });
  for (const auto& e : entries) {
    if (e.is_directory()) {
      const auto n = std::distance(fs::directory_iterator(e.path(), ec), fs::directory_iterator());
      out << "          " << e.path().filename().string() << "/ (" << n << " files)\n";
    } else {
      out << "          " << e.path().filename().string() << "\n";
    }
  }
}

void run_command(const RunArgs& args) {
  Scenario s = load_scenario(args.scenario);
  BackendSelection selection = scenario_backend_selection(s, args.backend, args.precision, args.threads);
  const std::string backend_choice = resolve_auto_backend(selection);
  if (!backend_choice.empty()) std::cout << "backend:  " << backend_choice << "\n";
  s.backend.name = selection.name;

  MeshReport mesh_report;
  const TetMesh mesh = load_scenario_mesh(s.mesh, &mesh_report);
  std::cout << "mesh:     " << s.mesh.path.string() << " -> " << mesh_report.points << " points, "
            << mesh_report.tets << " tets, min dihedral " << mesh_report.quality.min_dihedral_deg << " deg ("
            << (s.mesh.kind == MeshDef::Kind::Surface ? "meshed" : "read") << " in " << std::setprecision(3)
            << mesh_report.seconds << " s)\n"
            << std::setprecision(6);
  for (const std::string& n : mesh_report.notes) std::cout << "          note: " << n << "\n";

  const auto model_start = std::chrono::steady_clock::now();
  const Model model = build_scenario_model(s, mesh);
  const double model_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - model_start).count();
  auto backend = make_backend(selection, model, backend_tool(s));

  const fs::path outdir = args.outdir.empty() ? fs::path("out") / fs::path(args.scenario).stem() : fs::path(args.outdir);
  std::vector<std::string> observer_names;
  auto observers = make_observers(s, model, outdir, &observer_names);

  // dt_crit at rest and the start at rest (core/run/prepare_run.h); --plan stops before settling.
  PrepareRunOptions prepare_options;
  prepare_options.settle = !args.plan;
  prepare_options.threads = selection.threads;
  const PreparedRun prepared = prepare_run(s, model, prepare_options);
  const StabilityReport& stability = prepared.stability;

  if (args.plan) {
    print_plan(std::cout, s, model, *backend, observer_names);
    std::cout << format_stability_report(stability, s.time.dt, s.time.substeps, s.time.integrator);
    return;
  }
  const std::string step_warning = check_time_step(stability, s.time.dt, s.time.substeps, args.allow_unstable, s.time.integrator);
  if (!step_warning.empty()) std::cerr << "organsim: " << step_warning << "\n";
  // A check costs about one step on the CPU (organsim bench): every 10 ticks
  // keeps it near 2 % and still stops a blow-up within 10 ms. On the GPU it
  // drains the pipeline while non-finite positions are flagged on the device
  // every tick at no cost: every 50 ticks (Backend::default_check_interval_ticks).
  const int32_t check_interval =
      args.check_interval > 0 ? args.check_interval : backend->default_check_interval_ticks();
  BlowupMonitor monitor = prepared.blowup_monitor(s, s.time.dt, check_interval);

  // Start at rest under gravity (time.settle): the run begins from equilibrium.
  prepared.start(*backend);
  if (prepared.settled) std::cout << "settle:   " << describe(*prepared.settled) << "\n";

  RunOptions options;
  options.outdir = outdir;
  options.allow_unstable = args.allow_unstable;  // also after each topology change
  options.observers.push_back(&monitor);  // first: nothing else sees a blown-up state
  for (auto& o : observers) options.observers.push_back(o.get());
  RunProgress progress(s.time.ticks(), s.time.tick());  // a line on stderr, only when it is a terminal
  if (progress.enabled()) options.observers.push_back(&progress);
  options.meta_extra = {
      {"mesh", s.mesh.path.string()},
      {"mesh_kind", s.mesh.kind == MeshDef::Kind::Surface ? "surface" : "tet"},
      {"mesh_seconds", mesh_report.seconds},
      {"mesh_min_dihedral_deg", mesh_report.quality.min_dihedral_deg},
      {"model_seconds", model_seconds},
      {"tool", s.tool ? (s.tool->spec.mode == ToolMode::Push ? "push" : "pull") : "none"},
  };
  options.meta_extra.update(prepared.meta());
  if (!backend_choice.empty()) options.meta_extra["backend_choice"] = backend_choice;
  options.meta_extra["stability"]["check_interval_ticks"] = check_interval;
  std::cout << "run:      " << s.time.ticks() << " ticks of " << s.time.tick() << " s on " << backend->name()
            << " (" << backend->precision() << ", " << backend->device() << ")\n";
  std::cout.flush();
  RunResult result;
  try {
    result = run_scenario(s, model, *backend, options);
  } catch (const Error&) {
    if (s.outputs.forces) std::cerr << "organsim: the force log up to the failure is in " << (outdir / "forces.json").string() << "\n";
    throw;
  }
  double peak = 0;
  for (const Vec3& f : result.samples.force) peak = std::max(peak, f.norm());
  std::cout << "done:     " << result.samples.size() << " ticks in " << std::setprecision(3)
            << result.meta.wall_seconds << " s wall, " << std::setprecision(4) << result.meta.steps_per_second
            << " steps/s, peak tool force " << peak << " N\n";
  if (result.meta.extra.contains("device_at_end"))
    std::cout << "device:   " << result.meta.extra["device_at_end"].get<std::string>() << " (at the end)\n";
  std::cout << "real time: " << std::setprecision(3) << result.meta.real_time_factor
            << "x (simulated seconds per wall second, checks and outputs included; >= 1 keeps up with the clock)\n";
  if (s.tool && s.tool->spec.mode == ToolMode::Pull) {
    std::cout << "grasp:    " << result.grasped_points << " points attached"
              << (result.grasped_points == 0 ? " (none within grasp_radius: the tool pulled nothing)" : "") << "\n";
  }
  if (!result.forces_path.empty()) std::cout << "force log: " << result.forces_path.string() << "\n";
  if (const std::string line = integrator_summary(result.meta.extra.value("integrator", nlohmann::json())); !line.empty())
    std::cout << "implicit: " << line << "\n";
  std::cout << "outputs:  " << outdir.string() << "\n";
  print_output_files(std::cout, outdir);
  if (const std::string warning = integrator_warning(*backend); !warning.empty())
    throw Error(ErrorKind::SolverWarning, warning);
}

const bool run_registered = register_command("run", 20, [](CLI::App& root) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = root.add_subcommand(
      "run", "Run a scenario (JSON, SI units) and write OUTDIR/forces.json: tool force [N], torque [N m], "
             "tool position [m] and contacts at every haptic tick.");
  cmd->add_option("scenario", args->scenario, "Scenario file (see docs/scenarios.md)")->required();
  cmd->add_option("-o,--output", args->outdir, "Output folder (default: out/<scenario name>)");
  cmd->add_option("--backend", args->backend,
                  "auto, cpu or gl; overrides the scenario's backend (default auto: gl on a hardware GPU, "
                  "else cpu in float; gl by name never falls back)")
      ->check(CLI::IsMember({"auto", "cpu", "gl"}));
  cmd->add_option("--precision", args->precision, "double or float; overrides the scenario's precision")
      ->check(CLI::IsMember({"double", "float"}));
  cmd->add_option("--threads", args->threads, "CPU threads (0: all); overrides the scenario's backend.threads")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--plan", args->plan,
                "Print the model counts, the passes and buffers the step would use, without running");
  cmd->add_flag("--allow-unstable", args->allow_unstable,
                "Run even when time.dt exceeds the critical step dt_crit [s] (the blow-up check will likely stop it)");
  cmd->add_option("--check-interval", args->check_interval,
                  "Check for blow-up (non-finite, energy, strain, inversion) every N haptic ticks "
                  "(default 10 on cpu; 50 on gl, where each check is a GPU sync and non-finite positions are flagged on the GPU every tick)")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] { run_command(*args); });
});

}  // namespace
}  // namespace organsim::app
