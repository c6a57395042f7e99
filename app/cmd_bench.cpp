// `organsim bench`: median milliseconds per integration step on models of the
// paper's sizes (liver-like surface meshed to 1617, 6792, 7750, 28292 points),
// next to the paper's Table 1, with the machine it ran on. Honest numbers:
// warm-up first, then repetitions, median (min and max shown); each
// repetition ends with a read-back of the positions so asynchronous backends
// are timed until their work is done.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "app/backend_factory.h"
#include "app/bench_implicit.h"
#include "app/bench_materials.h"
#include "app/bench_timing.h"
#include "app/command.h"
#include "core/mesh/example_shapes.h"
#include "core/mesh/mesh_io.h"
#include "core/model/model.h"
#include "core/model/stiffness.h"
#include "core/render/frame_cost.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/scatter_step.h"
#include "core/stability/blowup_monitor.h"
#include "core/stability/critical_step.h"
#include "core/topology/change_cost.h"
#include "core/util/atomic_file.h"
#include "core/util/error.h"
#include "core/util/format.h"
#include "meshing/mesh_surface.h"

namespace organsim::app {
namespace {

// Substeps per haptic tick assumed when the blow-up check's cost is given as
// a share of a run (the liver scenarios' 1 ms tick of 0.1 ms steps).
constexpr int32_t kBenchSubsteps = 10;

// The paper's Table 1: ms per step for its models on two GPUs and one CPU.
struct PaperRow {
  const char* model;
  int32_t points, springs;
  double quadro_fx_3450, geforce_go_7900, xeon_3ghz;  // ms
};
constexpr PaperRow kPaper[] = {
    {"Bunny5", 1617, 8871, 0.179, 0.093, 0.99},
    {"Bunny6", 6792, 38030, 0.609, 0.406, 4.47},
    {"Liver", 7750, 48254, 0.689, 0.468, 5.5},
    {"Bunny7", 28292, 159353, 2.77, 2.06, 28.45},
};

const PaperRow* paper_row(int32_t target) {
  for (const PaperRow& r : kPaper) {
    if (r.points == target) return &r;
  }
  return nullptr;
}

struct BenchArgs {
  std::vector<int32_t> sizes{1617, 6792, 7750, 28292};
  std::vector<std::string> backends;    // empty: cpu, and gl when it can be created
  std::vector<std::string> precisions;  // empty: double and float on cpu, float on gl
  std::vector<std::string> simd;        // cpu kernels by target name; empty: every target this CPU runs
  int32_t threads = 0;
  int32_t gl_threads_per_point = 0;
  BenchSteps steps;           // warm-up, repetitions, steps per repetition (bench_timing.h)
  double dt = 1e-4;           // s
  double volume_modulus = 20000;  // Pa; 0 leaves the volume pass out
  bool nodal_volume = false;      // the averaged nodal volume term instead of the per-tet one
  double poisson_ratio = -1;      // >= 0: material.poisson_ratio (its own volume term or shear element), no volume_modulus
  std::string surface;        // default: the built-in liver-like surface (= examples/liver.off)
  bool exude = true;
  bool frames = true;         // also measure one rendered frame per model
  std::string json;           // --json FILE: the results as JSON ("-": on stdout instead of the table)
  bool materials = false;     // --materials: the material comparison (bench_materials.h) instead of the size table
  std::string materials_scenario = "scenarios/liver_suture.json";  // its sutured and unsutured rows
  bool implicit = false;      // --implicit: the integrators' comparison (bench_implicit.h) instead of the size table
  std::string tool = "none";  // none, or a pushing sphere touching the model: "surface" or "points" contact
};

// The bench's tool: a 2 cm sphere pressed 5 mm into the model's lowest
// point from below, moved with it as the model falls (--tool).
constexpr double kBenchToolRadius = 0.02, kBenchToolDepth = 0.005;  // m

BenchToolPlacement bench_tool_placement(const BenchArgs& args) {
  if (args.tool == "none") return {};
  return {kBenchToolRadius, kBenchToolDepth};
}

BackendTool bench_tool(const BenchArgs& args) {
  BackendTool tool;
  if (args.tool == "none") return tool;
  tool = {true, ToolMode::Push, kBenchToolRadius, 500.0,
          args.tool == "points" ? ToolContact::Points : ToolContact::Surface};
  tool.hertz_layer = tool.contact == ToolContact::Surface;  // as a scenario's sphere on the surface
  return tool;
}

struct Machine {
  std::string cpu = "unknown CPU";
  int32_t logical_cpus = 0;
  std::string load_average;  // /proc/loadavg's 1, 5, 15 min figures: a shared machine shows here
};

Machine read_machine() {
  Machine m;
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  bool named = false;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0 && !named) {
      m.cpu = line.substr(line.find(':') + 2);
      named = true;
    }
    if (line.rfind("processor", 0) == 0) ++m.logical_cpus;
  }
  if (m.logical_cpus == 0) m.logical_cpus = static_cast<int32_t>(std::thread::hardware_concurrency());
  std::ifstream load("/proc/loadavg");
  std::string a, b, c;
  if (load >> a >> b >> c) m.load_average = a + " " + b + " " + c;
  return m;
}

std::string utc_now() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  std::ostringstream s;
  s << std::put_time(&tm, "%Y-%m-%d %H:%M UTC");
  return s.str();
}

// The plain per-spring / per-tet scatter step (one thread, no layout) on the
// same model, precision and dt, timed the same way: the baseline of the
// speedup, measured in the same run so that machine load cancels out.
template <class Real>
BenchTiming time_scatter(const Model& model, const BenchArgs& args, double dt, std::vector<Vec3>& positions) {
  ScatterStep<Real> scatter(model);
  for (int32_t i = 0; i < args.steps.warmup; ++i) scatter.step(dt);
  std::vector<double> ms;
  for (int32_t r = 0; r < args.steps.repetitions; ++r) {
    const auto start = std::chrono::steady_clock::now();
    for (int32_t i = 0; i < args.steps.steps; ++i) scatter.step(dt);
    scatter.positions(positions);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ms.push_back(1e3 * seconds / args.steps.steps);
  }
  return summarise_ms(std::move(ms));
}

struct Row {
  int32_t target = 0;
  int32_t points = 0, springs = 0, tets = 0;
  double mesh_seconds = 0;
  double dt = 0, dt_crit = 0;  // s: the step used and the model's critical step
  std::string backend, precision, device;
  std::string kernel;   // cpu: the kernel's target ("avx2", ...); gl: empty
  BenchTiming timing;
  BenchTiming scatter;  // the plain scatter step, same model and precision, 1 thread
  Plan plan;
  double check_ms = 0;  // one blow-up check (positions read back included)
  int32_t check_interval = 10;  // the run's default ticks between checks on this backend
};

// Frame cost per model size (backend-independent: the renderer's own paths).
struct FrameRow {
  int32_t points = 0;
  FrameCost cost;
};

// One row's backend, precision and (cpu) kernel.
struct Configuration {
  std::string backend, precision, kernel;
};

// The cpu kernels a bench times side by side: every simd target this CPU
// runs (best first).
std::vector<std::string> cpu_kernels(const BenchArgs& args) {
  if (!args.simd.empty()) return args.simd;
  std::vector<std::string> out;
  for (const SimdTarget& t : simd_targets_supported()) out.push_back(t.name);
  return out;
}

std::vector<Configuration> configurations(const BenchArgs& args) {
  const std::vector<std::string> backends = args.backends.empty() ? backend_names() : args.backends;
  std::vector<Configuration> out;
  for (const std::string& b : backends) {
    std::vector<std::string> precisions = args.precisions;
    if (precisions.empty()) precisions = b == "cpu" ? std::vector<std::string>{"double", "float"} : std::vector<std::string>{"float"};
    for (const std::string& p : precisions) {
      if (b != "cpu") {
        out.push_back({b, p, ""});
        continue;
      }
      for (const std::string& k : cpu_kernels(args)) out.push_back({b, p, k});
    }
  }
  return out;
}

// Everything one bench run measured, printed as a table or written as JSON.
struct Results {
  Machine machine;
  std::string date;
  std::string surface_name;
  std::vector<Row> rows;
  std::vector<FrameRow> frame_rows;
  std::vector<std::pair<int32_t, ChangeCost>> change_rows;  // points, cost of one local cut
  std::string frames_unavailable;
  std::vector<std::pair<std::string, std::string>> unavailable;  // backend, reason
  std::vector<MaterialComparison> materials;  // --materials: one per size and precision
  std::vector<ImplicitComparison> implicit;   // --implicit: one per size
};

Results measure(const BenchArgs& args) {
  Results res;
  res.machine = read_machine();
  res.date = utc_now();
  TriangleMesh surface = args.surface.empty() ? make_liver_surface(4) : read_surface(args.surface);
  res.surface_name = args.surface.empty() ? "built-in liver-like surface (examples/liver.off)" : args.surface;
  const std::string& surface_name = res.surface_name;
  const bool explicit_backends = !args.backends.empty();
  const bool quiet = args.json == "-";  // the JSON alone on stdout, as before: no progress lines either

  std::vector<Row>& rows = res.rows;
  std::vector<FrameRow>& frame_rows = res.frame_rows;
  std::vector<std::pair<int32_t, ChangeCost>>& change_rows = res.change_rows;
  std::string& frames_unavailable = res.frames_unavailable;
  std::vector<std::pair<std::string, std::string>>& unavailable = res.unavailable;
  std::vector<Vec3> positions;
  for (const int32_t target : args.sizes) {
    MeshOptions mo;
    mo.target_points = target;
    mo.exude = args.exude;
    MeshReport report;
    const TetMesh mesh = mesh_surface(surface, mo, surface_name, &report);
    // Every row on the same thread count (the backend's own choice would
    // time each row on whatever count a moment of load favoured, and its
    // probes of the other count land in the timed steps).
    const int32_t threads = args.threads > 0 ? args.threads : std::max(1, static_cast<int32_t>(std::thread::hardware_concurrency()));
    if (args.implicit) {
      ImplicitBenchOptions ib;
      ib.threads = threads;
      ib.steps = args.steps;
      ib.quiet = quiet;
      res.implicit.push_back(measure_implicit(ib, mesh, surface_name, target));
      continue;
    }
    if (args.materials) {
      const std::vector<std::string> precisions = args.precisions.empty() ? std::vector<std::string>{"float"} : args.precisions;
      for (const std::string& precision : precisions) {
        MaterialBenchOptions mb;
        mb.backend = args.backends.empty() ? "cpu" : args.backends[0];
        mb.precision = precision;
        mb.threads = threads;
        mb.steps = args.steps;
        mb.dt = args.dt;
        mb.exude = args.exude;
        mb.suture_scenario = args.materials_scenario;
        mb.quiet = quiet;
        res.materials.push_back(measure_materials(mb, mesh, surface_name, target));
      }
      continue;
    }
    Material material;
    material.young_modulus = 8000;
    material.volume_modulus = args.volume_modulus;
    if (args.nodal_volume) material.volume_formulation = VolumeFormulation::Nodal;
    if (args.poisson_ratio >= 0) {
      material.poisson_ratio = args.poisson_ratio;
      material.volume_modulus = 0;
    }
    ModelOptions options;
    options.gravity = Vec3(0, 0, -9.81);  // a moving model, not one at rest
    const Model model = build_model(mesh, material, options, surface_name);
    // Finer meshes have a smaller critical step: time each model at a step
    // it is stable at (at most --dt), as a run would be.
    const double dt_crit = estimate_critical_step(model).dt_crit;
    const double dt = std::min(args.dt, 0.5 * dt_crit);
    if (!quiet) {
      std::cerr << "bench: " << target << " points asked, " << model.npoint() << " meshed in "
                << fixed(report.seconds, 2) << " s; dt_crit " << dt_crit << " s, dt " << dt << " s\n";
    }
    for (const auto& [name, precision, kernel] : configurations(args)) {
      BackendSelection sel;
      sel.name = name;
      sel.precision = precision;
      sel.cpu_kernel = kernel;
      sel.threads = args.threads;
      sel.gl_threads_per_point = args.gl_threads_per_point;
      std::unique_ptr<Backend> backend;
      try {
        backend = make_backend(sel, model, bench_tool(args));
      } catch (const Error& e) {
        // Asked for by name: fail. Tried by default (gl, or a precision it
        // does not offer): report why there is no row.
        if (explicit_backends) throw;
        const std::string what = name + " " + precision + (kernel.empty() ? "" : " " + kernel);
        if (std::none_of(unavailable.begin(), unavailable.end(), [&](const auto& u) { return u.first == what; })) {
          unavailable.emplace_back(what, e.what());
        }
        continue;
      }
      Row row;
      row.target = target;
      row.points = model.npoint();
      row.springs = model.nspring();
      row.tets = model.ntet();
      row.mesh_seconds = report.seconds;
      row.backend = backend->name();
      row.precision = backend->precision();
      row.kernel = kernel;
      row.plan = backend->plan();
      row.dt = dt;
      row.dt_crit = dt_crit;
      row.timing = time_backend(*backend, args.steps, dt, positions, bench_tool_placement(args));
      row.device = backend->device();  // after the timing: the thread count it ran on
      row.scatter = row.precision == "float" ? time_scatter<float>(model, args, dt, positions)
                                             : time_scatter<double>(model, args, dt, positions);
      row.check_ms = measure_check_ms(model, *backend);
      row.check_interval = backend->default_check_interval_ticks();
      rows.push_back(row);
    }
    change_rows.emplace_back(model.npoint(), measure_change_cost(model));
    if (args.frames) {
      try {
        frame_rows.push_back({model.npoint(), measure_frame_cost(model)});
      } catch (const Error& e) {
        frames_unavailable = e.what();
      }
    }
  }

  return res;
}

nlohmann::json to_json(const Results& res, const BenchArgs& args) {
  const Machine& machine = res.machine;
  nlohmann::json j;
  j["date"] = res.date;
  j["organsim_version"] = ORGANSIM_VERSION;
  j["machine"] = {{"cpu", machine.cpu}, {"logical_cpus", machine.logical_cpus},
                  {"load_average_at_start", machine.load_average}};
  j["settings"] = {{"sizes", args.sizes}, {"threads", args.threads},
                   {"warmup_steps", args.steps.warmup}, {"repetitions", args.steps.repetitions},
                   {"steps_per_repetition", args.steps.steps}, {"dt", args.dt},
                   {"volume_modulus", args.volume_modulus}, {"young_modulus", 8000},
                   {"volume_formulation", args.nodal_volume ? "nodal" : "per_tet"},
                   {"poisson_ratio", args.poisson_ratio >= 0 ? nlohmann::json(args.poisson_ratio) : nlohmann::json()},
                   {"gravity", true}, {"tool", args.tool}, {"exude", args.exude}, {"surface", res.surface_name}};
  j["rows"] = nlohmann::json::array();
  for (const Row& r : res.rows) {
    nlohmann::json jr = {{"target_points", r.target}, {"points", r.points}, {"springs", r.springs},
                         {"tets", r.tets}, {"dt", r.dt}, {"dt_crit", r.dt_crit},
                         {"backend", r.backend}, {"precision", r.precision},
                         {"kernel", r.kernel.empty() ? nlohmann::json() : nlohmann::json(r.kernel)},
                         {"device", r.device}, {"median_ms", r.timing.median_ms},
                         {"min_ms", r.timing.min_ms}, {"max_ms", r.timing.max_ms},
                         {"steps_per_second", 1e3 / r.timing.median_ms},
                         {"scatter_median_ms", r.scatter.median_ms},
                         {"speedup_over_scatter", r.scatter.median_ms / r.timing.median_ms},
                         {"dispatches_per_step", r.plan.dispatches_per_step},
                         {"syncs_per_step", r.plan.syncs_per_step}, {"blowup_check_ms", r.check_ms},
                         {"blowup_check_interval_ticks", r.check_interval}};
    nlohmann::json passes = nlohmann::json::array();
    for (const PassInfo& p : r.plan.passes) passes.push_back(p.name);
    jr["passes"] = passes;
    if (const PaperRow* p = paper_row(r.target)) {
      jr["paper"] = {{"model", p->model}, {"points", p->points}, {"springs", p->springs},
                     {"quadro_fx_3450_ms", p->quadro_fx_3450}, {"geforce_go_7900_ms", p->geforce_go_7900},
                     {"xeon_3ghz_ms", p->xeon_3ghz}};
    }
    j["rows"].push_back(jr);
  }
  j["frames"] = nlohmann::json::array();
  for (const FrameRow& f : res.frame_rows) {
    const FrameCost& c = f.cost;
    j["frames"].push_back({{"points", f.points}, {"width", c.width}, {"height", c.height},
                           {"triangles", c.triangles}, {"renderer", c.renderer}, {"upload_ms", c.upload_ms},
                           {"render_ms", c.render_ms}, {"readback_ms", c.readback_ms}, {"png_ms", c.png_ms},
                           {"video_ms", c.video_ms}, {"run_loop_ms", c.run_loop_ms()}});
  }
  if (!res.frames_unavailable.empty()) j["frames_unavailable"] = res.frames_unavailable;
  j["topology_change"] = nlohmann::json::array();
  for (const auto& [points, c] : res.change_rows) {
    j["topology_change"].push_back({{"points", points}, {"faces_separated", c.faces_separated},
                                    {"points_added", c.points_added}, {"detect_ms", c.detect_ms},
                                    {"model_ms", c.model_ms}, {"backend_rebuild_ms", c.backend_ms},
                                    {"dt_check_ms", c.dt_check_ms}, {"total_ms", c.total_ms()},
                                    {"full_dt_crit_ms", c.dt_crit_ms},
                                    {"guaranteed_over_dt_crit", c.guaranteed_over_dt_crit}});
  }
  j["unavailable"] = nlohmann::json::array();
  for (const auto& [b, why] : res.unavailable) j["unavailable"].push_back({{"backend", b}, {"reason", why}});
  if (args.materials) {
    j["settings"]["materials_scenario"] = args.materials_scenario;
    j["materials"] = nlohmann::json::array();
    for (const MaterialComparison& c : res.materials) {
      j["materials"].push_back(to_json(c));
    }
  }
  if (args.implicit) {
    j["implicit"] = nlohmann::json::array();
    for (const ImplicitComparison& c : res.implicit) j["implicit"].push_back(to_json(c));
  }
  return j;
}

void print_machine(const Results& res) {
  const Machine& machine = res.machine;
  std::cout << "organsim bench, " << res.date << "\n";
  std::cout << "machine: " << machine.cpu << ", " << machine.logical_cpus << " logical CPUs, load average "
            << machine.load_average << " at start\n";
}

// --materials: the comparison instead of the size table.
void print_material_comparisons(const Results& res, const BenchArgs& args) {
  print_machine(res);
  std::cout << "step:    springs + dampers + the material's terms + gravity + Verlet, no tool; dt " << args.dt
            << " s or half the model's dt_crit if smaller; " << args.steps.warmup << " warm-up steps, then "
            << args.steps.repetitions << " repetitions of " << args.steps.steps << " steps\n";
  std::cout << "models:  " << res.surface_name << " and " << args.materials_scenario
            << "'s surface, meshed to the same point count\n";
  for (const MaterialComparison& c : res.materials) {
    std::cout << "\n";
    print_materials(std::cout, c);
  }
}

// --implicit: the integrators' comparison instead of the size table.
void print_implicit_comparisons(const Results& res, const BenchArgs& args) {
  print_machine(res);
  std::cout << "step:    springs + dampers + nodal volume term + gravity + a 2 cm sphere 5 mm into the lowest point "
            << "(surface contact), the top tenth fixed; Verlet at the guaranteed step, implicit Euler (block Jacobi) at 1 ms, implicit damping within the undamped limit; "
            << args.steps.warmup << " warm-up steps, then " << args.steps.repetitions << " repetitions of "
            << args.steps.steps << " steps (implicit rows: a tenth of both)\n";
  std::cout << "models:  " << res.surface_name << "\n";
  for (const ImplicitComparison& c : res.implicit) {
    std::cout << "\n";
    print_implicit(std::cout, c);
  }
}

void print_table(const Results& res, const BenchArgs& args) {
  print_machine(res);
  const std::vector<Row>& rows = res.rows;
  const std::vector<FrameRow>& frame_rows = res.frame_rows;
  const std::string material_terms =
      args.poisson_ratio >= 0 ? " (poisson_ratio " + format_number(args.poisson_ratio, "%.3g") +
                                    (args.poisson_ratio < kShearElementBelowPoissonRatio ? ": + shear element)"
                                                                                         : ": + its volume term)")
      : args.volume_modulus > 0 ? (args.nodal_volume ? " + nodal volume" : " + volume")
                                : "";
  std::cout << "step:    springs + dampers" << material_terms
            << " + gravity"
            << (args.tool == "none" ? ""
                                    : " + a 2 cm sphere 5 mm into the lowest point (" + args.tool + " contact)")
            << " + Verlet, dt " << args.dt << " s or half the model's dt_crit if smaller; "
            << args.steps.warmup << " warm-up steps, then "
            << args.steps.repetitions << " repetitions of " << args.steps.steps << " steps; median (min..max) ms per step\n";
  std::cout << "models:  " << res.surface_name << " meshed to the paper's point counts"
            << (args.exude ? " (with exudation)" : "") << "\n\n";
  std::cout << std::left << std::setw(8) << "paper" << std::right << std::setw(7) << "points" << std::setw(8)
            << "springs" << std::setw(8) << "tets" << std::setw(8) << "dt us" << "  " << std::left << std::setw(8)
            << "backend" << std::setw(7)
            << "prec" << std::setw(8) << "kernel" << std::right << std::setw(10) << "median ms" << std::setw(21) << "(min..max)"
            << "  | paper ms: " << "QuadroFX3450 GeForceGo7900 Xeon3GHz\n";
  for (const Row& r : rows) {
    const PaperRow* p = paper_row(r.target);
    std::cout << std::left << std::setw(8) << (p ? p->model : "-") << std::right << std::setw(7) << r.points
              << std::setw(8) << r.springs << std::setw(8) << r.tets << std::setw(8) << fixed(1e6 * r.dt, 1) << "  "
              << std::left << std::setw(8)
              << r.backend << std::setw(7) << r.precision << std::setw(8) << (r.kernel.empty() ? "-" : r.kernel)
              << std::right << std::setw(10) << fixed(r.timing.median_ms, 4) << std::setw(21)
              << ("(" + fixed(r.timing.min_ms, 4) + ".." + fixed(r.timing.max_ms, 4) + ")") << "  | ";
    if (p) {
      std::cout << std::setw(12) << fixed(p->quadro_fx_3450, 3) << std::setw(14) << fixed(p->geforce_go_7900, 3)
                << std::setw(9) << fixed(p->xeon_3ghz, 2) << "   (" << p->points << " pts, " << p->springs
                << " springs)";
    } else {
      std::cout << "(no paper figure for this size)";
    }
    std::cout << "\n";
  }
  std::cout << "\ndevices:\n";
  std::vector<std::string> seen;
  for (const Row& r : rows) {
    const std::string key = r.backend + " " + r.precision + ": " + r.device + ", " +
                            std::to_string(r.plan.dispatches_per_step) + " dispatch(es) and " +
                            std::to_string(r.plan.syncs_per_step) + " CPU-GPU sync(s) per step";
    if (std::find(seen.begin(), seen.end(), key) == seen.end()) {
      seen.push_back(key);
      std::cout << "  " << key << " (" << r.points << " points)\n";
    }
  }
  for (const auto& [b, why] : res.unavailable) std::cout << "  " << b << ": not measured: " << why << "\n";

  std::cout << "\nspeedup over the plain per-spring / per-tet scatter step (1 thread, no layout, same model,\n"
               "precision and dt, timed in this run), median ms per step:\n";
  for (const Row& r : rows)
    std::cout << "  " << std::setw(7) << r.points << " points  " << std::left << std::setw(4) << r.backend
              << std::setw(7) << r.precision << std::setw(8) << (r.kernel.empty() ? "-" : r.kernel) << std::right
              << std::setw(9) << fixed(r.timing.median_ms, 4) << "  scatter " << std::setw(8) << fixed(r.scatter.median_ms, 4) << "  speedup "
              << fixed(r.scatter.median_ms / r.timing.median_ms, 2) << "x\n";

  std::cout << "\nblow-up check (non-finite, energy, strain, inversion; positions read back), ms per check:\n";
  for (const Row& r : rows)
    std::cout << "  " << std::setw(7) << r.points << " points  " << std::left << std::setw(4) << r.backend
              << std::setw(7) << r.precision << std::right << std::setw(8) << fixed(r.check_ms, 4) << "  ("
              << fixed(100 * r.check_ms / r.timing.median_ms, 0) << " % of one step; run checks every "
              << r.check_interval << " ticks by default: "
              << fixed(100 * r.check_ms / (r.check_interval * kBenchSubsteps * r.timing.median_ms), 1)
              << " % of a run of " << kBenchSubsteps << " substeps per tick)\n";
  if (!frame_rows.empty()) {
    std::cout << "\nframes (" << frame_rows.front().cost.width << "x" << frame_rows.front().cost.height << ", "
              << frame_rows.front().cost.renderer << "), median ms per frame:\n";
    std::cout << "   points  triangles  upload  render  readback | run loop pays | png  mp4v (writer thread)\n";
    for (const FrameRow& f : frame_rows) {
      const FrameCost& c = f.cost;
      std::cout << std::setw(9) << f.points << std::setw(11) << c.triangles << std::setw(8) << fixed(c.upload_ms, 2)
                << std::setw(8) << fixed(c.render_ms, 2) << std::setw(10) << fixed(c.readback_ms, 2) << " | "
                << std::setw(13) << fixed(c.run_loop_ms(), 2) << " | " << std::setw(4) << fixed(c.png_ms, 1)
                << std::setw(6) << fixed(c.video_ms, 1) << "\n";
    }
  }
  if (!res.frames_unavailable.empty()) std::cout << "\nframes: not measured: " << res.frames_unavailable << "\n";

  std::cout << "\none topology change (a local cut through the model's middle, 4 x 3 spring lengths, cpu double, 1 "
               "thread), median ms:\n";
  std::cout << "   points  faces  copies  detect  split+model  backend rebuild  dt check   total |  full dt_crit"
               "  guaranteed/dt_crit\n";
  for (const auto& [points, c] : res.change_rows) {
    std::cout << std::setw(9) << points << std::setw(7) << c.faces_separated << std::setw(8) << c.points_added
              << std::setw(8) << fixed(c.detect_ms, 2) << std::setw(13) << fixed(c.model_ms, 2) << std::setw(17)
              << fixed(c.backend_ms, 2) << std::setw(10) << fixed(c.dt_check_ms, 3) << std::setw(8)
              << fixed(c.total_ms(), 2) << " | " << std::setw(13) << fixed(c.dt_crit_ms, 1) << std::setw(20)
              << fixed(c.guaranteed_over_dt_crit, 2) << "\n";
  }
}

void run_bench(const BenchArgs& args) {
  if (args.steps.repetitions < 1 || args.steps.steps < 1 || args.steps.warmup < 0) {
    throw Error(ErrorKind::Usage, "bench: --repetitions and --steps must be >= 1, --warmup >= 0");
  }
  if (!args.json.empty() && args.json != "-") {
    // Found out before the minutes of measuring, not after.
    const std::filesystem::path folder = std::filesystem::path(args.json).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder)) {
      throw Error(ErrorKind::Output, args.json + ": cannot write: " + folder.string() + " is not a folder");
    }
  }
  const Results res = measure(args);
  if (args.json == "-") {
    std::cout << to_json(res, args).dump(2) << "\n";
    return;
  }
  if (args.implicit) {
    print_implicit_comparisons(res, args);
  } else if (args.materials) {
    print_material_comparisons(res, args);
  } else {
    print_table(res, args);
  }
  // The same figures as the table, as a data file (docs/bench/ keeps one per
  // machine and date); written whole or not at all.
  if (!args.json.empty()) {
    write_file_atomically(args.json, [&](std::ostream& out) { out << to_json(res, args).dump(2) << "\n"; });
    std::cout << "\nwrote " << args.json << "\n";
  }
}

std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

const bool bench_registered = register_command("bench", 60, [](CLI::App& root) {
  auto args = std::make_shared<BenchArgs>();
  auto backends = std::make_shared<std::string>();
  auto precisions = std::make_shared<std::string>();
  CLI::App* cmd = root.add_subcommand(
      "bench", "Median ms per integration step on models of the paper's sizes, next to the paper's Table 1");
  cmd->add_option("--sizes", args->sizes, "Target point counts (default: 1617 6792 7750 28292, the paper's models)")
      ->delimiter(',')
      ->check(CLI::Range(10, 10'000'000));
  cmd->add_option("--backend", *backends, "Comma-separated backends (default: cpu, and gl when it can be created)");
  cmd->add_option("--precision", *precisions, "Comma-separated precisions (default: double,float on cpu; float on gl)");
  cmd->add_option("--threads", args->threads, "CPU threads (0: the backend's choice)")->check(CLI::NonNegativeNumber);
  auto simd = std::make_shared<std::string>();
  cmd->add_option("--simd", *simd,
                  "Comma-separated SIMD targets of the cpu kernel to time side by side (e.g. avx3,avx2,sse4,scalar; "
                  "default: every target this CPU runs)");
  cmd->add_option("--gl-threads-per-point", args->gl_threads_per_point,
                  "GL invocations sharing one point's gathers, 1 to 16 (0: 1 on a software renderer, 8 on a GPU)")
      ->check(CLI::Range(0, 16));
  cmd->add_option("--warmup", args->steps.warmup, "Warm-up steps before timing (default 200)");
  cmd->add_option("--repetitions", args->steps.repetitions, "Timed repetitions; the median is reported (default 7)");
  cmd->add_option("--steps", args->steps.steps, "Steps per repetition (default 200)");
  cmd->add_option("--dt", args->dt, "Integration step, s (default 1e-4; half the model's critical step if that is smaller)")->check(CLI::PositiveNumber);
  cmd->add_option("--volume-modulus", args->volume_modulus, "Pa; 0 leaves the volume pass out (default 20000)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--nodal-volume", args->nodal_volume,
                "The averaged nodal volume term (material.volume_formulation \"nodal\") instead of the per-tet one");
  cmd->add_option("--poisson-ratio", args->poisson_ratio,
                  "Material with this Poisson ratio instead of --volume-modulus (below 0.25 it has the shear element, "
                  "docs/physics.md)")
      ->check(CLI::Range(0.0, 0.4999));
  cmd->add_flag("--materials", args->materials,
                "Instead of the size table: the materials' cost side by side on one backend (cpu, or --backend gl; per-tet volume_modulus, "
                "poisson_ratio 0.45 and 0.2, a scenario before and after its sutures), at --sizes (default 7750) in "
                "--precision (default float), with the ratios of the medians");
  cmd->add_flag("--implicit", args->implicit,
                "Instead of the size table: the integrators side by side on the cpu backend in double (Verlet and "
                "implicit Euler, a soft and a stiff liver hung by its top, a sphere pressing), at --sizes (default "
                "7750), with CG iterations and ms per CG iteration");
  cmd->add_option("--materials-scenario", args->materials_scenario,
                  "The scenario with sutures for --materials, meshed to each size (default "
                  "scenarios/liver_suture.json)")
      ->type_name("FILE");
  cmd->add_flag("!--no-frames", args->frames, "Skip the per-frame rendering cost");
  cmd->add_option("--tool", args->tool,
                  "A pushing tool touching the model during the timing: 'none' (default), 'surface' or 'points' "
                  "contact (a 2 cm sphere 5 mm into the lowest point, following it)")
      ->check(CLI::IsMember({"none", "surface", "points"}));
  cmd->add_option("--surface", args->surface, "Closed surface to mesh (default: the built-in liver-like surface)");
  cmd->add_flag("--exude,!--no-exude", args->exude, "Sliver exudation when meshing (default on)");
  cmd->add_option("--json", args->json,
                  "Also write the results as JSON to FILE (written whole or not at all); - prints the JSON on stdout "
                  "instead of the table")
      ->type_name("FILE");
  CLI::Option* sizes_option = cmd->get_option("--sizes");
  cmd->callback([args, backends, precisions, sizes_option, simd] {
    args->backends = split_list(*backends);
    args->simd = split_list(*simd);
    for (const std::string& k : args->simd)
      simd_target_named(k, "bench --simd");
    if (args->implicit && args->materials)
      throw Error(ErrorKind::Usage, "bench: --implicit and --materials are two comparisons: ask for one");
    if (args->implicit && sizes_option->count() == 0) args->sizes = {7750};  // the paper's liver
    if (args->materials) {
      if (sizes_option->count() == 0) args->sizes = {7750};  // the paper's liver
      if (args->backends.size() > 1) {
        throw Error(ErrorKind::Usage, "bench: --materials times one backend, cpu (default) or gl, not " + *backends);
      }
    }
    args->precisions = split_list(*precisions);
    for (const std::string& p : args->precisions) {
      if (p != "double" && p != "float") {
        throw Error(ErrorKind::Usage, "bench: unknown precision \"" + p + "\": expected double or float");
      }
    }
    for (const std::string& b : args->backends) {
      if (std::find(backend_names().begin(), backend_names().end(), b) == backend_names().end()) {
        throw Error(ErrorKind::Usage, "bench: unknown backend \"" + b + "\": expected cpu or gl");
      }
    }
    run_bench(*args);
  });
});

}  // namespace
}  // namespace organsim::app
