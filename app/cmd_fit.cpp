// `organsim fit SCENARIO.json --measured curve.csv --param material.young_modulus[,material.poisson_ratio,...]`
// Calibration: the material parameters whose simulated tool force best
// matches a measured force-time or force-displacement curve (least squares
// over the force samples; Levenberg-Marquardt on finite differences, a
// bounded number of iterations, one CPU double-precision run per
// evaluation). Writes fit.json, fit.png and the fitted run's forces.json.
// SI units.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "app/command.h"
#include "app/scenario_mesh.h"
#include "core/fit/least_squares.h"
#include "core/fit/measured_curve.h"
#include "core/model/stiffness.h"
#include "core/render/xy_plot.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/sim/cpu_backend.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim::app {
namespace {

namespace fs = std::filesystem;

struct FitArgs {
  std::string scenario, measured, outdir;
  std::vector<std::string> params;
  int32_t max_iterations = 20;
};

// A parameter `fit` can move: where it lives in the Material, its bounds and
// whether it is searched in log space.
struct ParameterSlot {
  const char* name;
  double lower, upper;
  bool log;
  std::function<double&(Material&)> ref;
};

const std::vector<ParameterSlot>& parameter_slots() {
  static const std::vector<ParameterSlot> slots{
      {"material.young_modulus", 1.0, 1e10, true, [](Material& m) -> double& { return m.young_modulus; }},
      {"material.poisson_ratio", kMinPoissonRatio, 0.49, false,
       [](Material& m) -> double& {
         if (!m.poisson_ratio) m.poisson_ratio = 0.25;  // the springs' own ratio: where the old rule is
         return *m.poisson_ratio;
       }},
      {"material.volume_modulus", 0.0, 1e10, false, [](Material& m) -> double& { return m.volume_modulus; }},
      {"material.density", 1.0, 1e5, true, [](Material& m) -> double& { return m.density; }},
      {"material.spring_damping_time", 1e-7, 1.0, true, [](Material& m) -> double& { return m.spring_damping_time; }},
      {"material.viscous_damping", 1e-6, 1e4, true, [](Material& m) -> double& { return m.viscous_damping; }},
  };
  return slots;
}

const ParameterSlot& slot_named(const std::string& name) {
  for (const ParameterSlot& s : parameter_slots())
    if (name == s.name) return s;
  std::string known;
  for (const ParameterSlot& s : parameter_slots()) known += std::string(known.empty() ? "" : ", ") + s.name;
  throw Error(ErrorKind::Usage, "--param: unknown parameter '" + name + "' (expected one of " + known + ")");
}

// One simulation with the given material, set up as `organsim run` sets up
// a run (core/run/prepare_run.h): CPU double precision, from the scenario's
// start at rest (time.settle, settled again for this material), watched by
// the blow-up monitor; at the scenario's dt unless the material makes it
// unstable, then at a stable dt that keeps the haptic tick (so the force
// samples stay at the same times).
RunResult simulate(Scenario s, const TetMesh& mesh, const Material& material, RunOptions options) {
  s.material = material;
  const Model model = build_scenario_model(s, mesh);
  const PreparedRun prepared = prepare_run(s, model);
  if (s.time.dt > prepared.stability.dt_crit) {
    const StepSuggestion step = suggest_step(prepared.stability, s.time.tick());
    s.time.dt = step.dt;
    s.time.substeps = step.substeps;
  }
  CpuBackendOptions cpu;
  cpu.precision = Precision::Double;
  cpu.threads = s.backend.threads;
  auto backend = make_cpu_backend(model, backend_tool(s), cpu);
  prepared.start(*backend);
  BlowupMonitor monitor = prepared.blowup_monitor(s, s.time.dt, backend->default_check_interval_ticks());
  options.observers.insert(options.observers.begin(), &monitor);
  options.meta_extra.update(prepared.meta());
  return run_scenario(s, model, *backend, options);
}

void fit_command(const FitArgs& args) {
  Scenario s = load_scenario(args.scenario);
  if (s.time.integrator != Integrator::Verlet)
    throw Error(ErrorKind::Usage, args.scenario + ": organsim fit simulates with Verlet only (time.integrator \"" +
                                      integrator_name(s.time.integrator) + "\" is not yet one it fits with)");
  if (!s.tool) throw Error(ErrorKind::Scenario, args.scenario + ": tool: fit needs a tool whose force it compares");
  std::vector<const ParameterSlot*> slots;
  std::vector<FitParameter> parameters;
  for (const std::string& name : args.params) {
    const ParameterSlot& slot = slot_named(name);
    for (const ParameterSlot* seen : slots)
      if (seen == &slot) throw Error(ErrorKind::Usage, "--param: '" + name + "' given twice");
    Material m = s.material;
    const double start = slot.ref(m);
    if (start < slot.lower || start > slot.upper)
      throw Error(ErrorKind::Scenario, args.scenario + ": " + name + ": start value " + format_number(start, "%.6g") +
                                           " outside the range fit searches [" + format_number(slot.lower, "%.6g") +
                                           ", " + format_number(slot.upper, "%.6g") + "]");
    slots.push_back(&slot);
    parameters.push_back({name, start, slot.lower, slot.upper, slot.log});
  }
  if (s.material.spring_stiffness)
    throw Error(ErrorKind::Scenario, args.scenario + ": material.spring_stiffness: fit needs young_modulus instead");
  if (!s.materials.empty())
    throw Error(ErrorKind::Scenario, args.scenario + ": materials: fit adjusts one `material`; per-label materials are not fitted");
  const MeasuredCurve curve = read_measured_curve(args.measured);

  const TetMesh mesh = load_scenario_mesh(s.mesh);
  const Vec3 tool_start = s.tool->spec.position_at(0);
  auto material_for = [&](const std::vector<double>& values) {
    Material m = s.material;
    for (size_t i = 0; i < slots.size(); ++i) slots[i]->ref(m) = values[i];
    return m;
  };
  RunOptions quiet;
  Scenario no_files = s;
  no_files.outputs = OutputsDef{};
  no_files.outputs.forces = false;
  auto columns_for = [&](const std::vector<double>& values) {
    const RunResult r = simulate(no_files, mesh, material_for(values), quiet);
    return simulated_columns(curve, r.samples, tool_start);
  };
  auto residual = [&](const std::vector<double>& values) {
    std::vector<double> out;
    try {
      const auto sim = columns_for(values);
      for (size_t k = 0; k < sim.size(); ++k)
        for (size_t i = 0; i < sim[k].size(); ++i) out.push_back(sim[k][i] - curve.force[k][i]);
    } catch (const Error& e) {
      if (e.kind() != ErrorKind::Numerical) throw;
      // A run that blew up or was refused: an infeasible point for the search.
      size_t n = 0;
      for (const auto& c : curve.force) n += c.size();
      out.assign(n, NAN);
    }
    return out;
  };

  const bool tty = isatty(2);
  LeastSquaresOptions ls;
  ls.max_iterations = args.max_iterations;
  const LeastSquaresResult fit =
      least_squares(parameters, residual, ls, [&](int32_t it, double cost, const std::vector<double>& v) {
        if (!tty) return;
        std::cerr << "iteration " << it << "/" << args.max_iterations << ": residual rms "
                  << format_number(std::sqrt(2 * cost / static_cast<double>(curve.x.size() * curve.columns.size())),
                                   "%.4g")
                  << " N";
        for (size_t i = 0; i < v.size(); ++i)
          std::cerr << ", " << parameters[i].name << " " << format_number(v[i], "%.5g");
        std::cerr << "\n";
      });

  const fs::path outdir = args.outdir.empty() ? fs::path("out") / (fs::path(args.scenario).stem().string() + "_fit")
                                              : fs::path(args.outdir);
  fs::create_directories(outdir);
  const double samples = static_cast<double>(curve.x.size() * curve.columns.size());
  const double rms = std::sqrt(2 * fit.cost / samples);
  const auto start_columns = columns_for([&] {
    std::vector<double> v;
    for (const FitParameter& p : parameters) v.push_back(p.start);
    return v;
  }());
  const Material fitted = material_for(fit.values);
  nlohmann::json j;
  j["scenario"] = args.scenario;
  j["measured"] = args.measured;
  j["units"] = "SI: moduli Pa, force N, t s, displacement m";
  j["method"] = "Levenberg-Marquardt, forward-difference Jacobian, CPU double runs";
  j["parameters"] = nlohmann::json::array();
  for (size_t i = 0; i < parameters.size(); ++i)
    j["parameters"].push_back({{"name", parameters[i].name}, {"start", parameters[i].start},
                               {"fitted", fit.values[i]}, {"lower", parameters[i].lower},
                               {"upper", parameters[i].upper}});
  j["residual_rms"] = rms;
  j["iterations"] = fit.iterations;
  j["evaluations"] = fit.evaluations;
  j["converged"] = fit.converged;
  j["stop_reason"] = fit.stop_reason;
  j["cost_history"] = fit.cost_history;
  const EffectiveElasticity e = effective_elasticity(fitted);
  j["effective_elasticity"] = {{"young_modulus", e.young_modulus}, {"poisson_ratio", e.poisson_ratio}};

  // The fitted run, with its force log: the fit's figures go into its meta.
  RunOptions final_run;
  final_run.outdir = outdir;
  final_run.meta_extra["fit"] = j;
  Scenario log_only = s;
  log_only.outputs = OutputsDef{};
  log_only.outputs.forces = true;
  const RunResult best = simulate(log_only, mesh, fitted, final_run);
  const auto best_columns = simulated_columns(curve, best.samples, tool_start);
  j["curve"]["x"] = curve.x;
  j["curve"]["abscissa"] = curve.abscissa == MeasuredCurve::Abscissa::Time ? "t" : "displacement";
  for (size_t k = 0; k < curve.columns.size(); ++k)
    j["curve"][curve.columns[k]] = {{"measured", curve.force[k]}, {"start", start_columns[k]},
                                    {"fitted", best_columns[k]}};
  write_file_atomically(outdir / "fit.json", [&](std::ostream& out) { out << j.dump(2) << "\n"; });

  std::vector<XySeries> series;
  for (size_t k = 0; k < curve.columns.size(); ++k) {
    series.push_back({"measured " + curve.columns[k], curve.x, curve.force[k], true, false});
    series.push_back({"start " + curve.columns[k], curve.x, start_columns[k], false, true});
    series.push_back({"fitted " + curve.columns[k], curve.x, best_columns[k], false, true});
  }
  XyPlotOptions plot;
  plot.title = "fit: residual rms " + format_number(rms, "%.3g") + " N";
  plot.x_label = curve.abscissa == MeasuredCurve::Abscissa::Time ? "t (s)" : "tool displacement (m)";
  plot.y_label = "force (N)";
  write_xy_plot(outdir / "fit.png", series, plot);

  for (size_t i = 0; i < parameters.size(); ++i)
    std::cout << parameters[i].name << ": " << format_number(parameters[i].start, "%.6g") << " -> "
              << format_number(fit.values[i], "%.6g") << "\n";
  std::cout << "residual rms " << format_number(rms, "%.4g") << " N after " << fit.iterations << " iterations ("
            << fit.evaluations << " runs, " << fit.stop_reason << ")\n";
  std::cout << "fit: " << (outdir / "fit.json").string() << ", fit.png, forces.json\n";
}

const bool fit_registered = register_command("fit", 47, [](CLI::App& root) {
  auto args = std::make_shared<FitArgs>();
  CLI::App* cmd = root.add_subcommand(
      "fit", "Calibrate material parameters (Pa, kg/m^3, s) so the simulated tool force [N] matches a measured "
             "force-time or force-displacement curve (CSV); writes fit.json, fit.png and forces.json");
  cmd->add_option("scenario", args->scenario, "Scenario file; its values are the starting point")->required();
  cmd->add_option("--measured", args->measured,
                  "CSV: header 't' or 'displacement' (s or m), then force, fx, fy and/or fz columns (N)")
      ->required();
  cmd->add_option("--param", args->params,
                  "Parameters to fit, comma-separated (material.young_modulus, material.poisson_ratio, "
                  "material.volume_modulus, material.density, material.spring_damping_time, "
                  "material.viscous_damping)")
      ->required()
      ->delimiter(',');
  cmd->add_option("-o,--output", args->outdir, "Output folder (default: out/<scenario name>_fit)");
  cmd->add_option("--max-iterations", args->max_iterations, "Most Jacobian evaluations (default 20)")
      ->check(CLI::PositiveNumber);
  cmd->callback([args] { fit_command(*args); });
});

}  // namespace
}  // namespace organsim::app
