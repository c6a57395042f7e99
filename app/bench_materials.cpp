#include "app/bench_materials.h"

#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/backend_factory.h"
#include "app/scenario_mesh.h"
#include "core/model/model.h"
#include "core/run/prepare_run.h"
#include "core/run/run.h"
#include "core/scenario/scenario.h"
#include "core/stability/critical_step.h"
#include "core/util/error.h"

namespace organsim::app {
namespace {

// The aims for the ratios of medians (docs/bench.md): the validated
// materials and sutures should cost little more than the simplest step.
constexpr double kNodalTarget = 1.3;
constexpr double kShearTarget = 2.0;
constexpr double kSutureTarget = 1.1;

// The bench's material (cmd_bench.cpp: E 8 kPa, the defaults otherwise) in
// each of the three forms compared.
Material bench_material(double poisson_ratio) {
  Material m;
  m.young_modulus = 8000;
  if (poisson_ratio >= 0) {
    m.poisson_ratio = poisson_ratio;
  } else {
    m.volume_modulus = 20000;
  }
  return m;
}

// "simd (avx2)", "simd (sse4)", ... from a CPU backend's device line ("...,
// simd (avx2) kernel"): what follows its last ", " up to " kernel".
std::string kernel_of(const std::string& device) {
  const std::string suffix = " kernel";
  if (device.size() < suffix.size() || device.compare(device.size() - suffix.size(), suffix.size(), suffix) != 0)
    return "?";
  const std::string head = device.substr(0, device.size() - suffix.size());
  const size_t comma = head.rfind(", ");
  return comma == std::string::npos ? head : head.substr(comma + 2);
}

// Keeps the Model versions a run makes: the last one without sutures and the
// first one with them.
struct SutureVersions final : RunObserver {
  std::optional<Model> unsutured, sutured;
  void on_tick(const Model&, Backend&, const TickInfo&) override {}
  void on_topology_changed(const Model& next, Backend&) override {
    if (next.nsuture() == 0) {
      unsutured = next;
    } else if (!sutured) {
      sutured = next;
    }
  }
};

// The suture scenario meshed to `target_points`, run (its events, gravity,
// fixed points; no outputs) until a tick after its last suture event: the
// Model versions just before and just after the sutures were tied.
std::pair<Model, Model> suture_models(const MaterialBenchOptions& options, int32_t target_points) {
  Scenario s = load_scenario(options.suture_scenario);
  const std::string file = options.suture_scenario.string();
  if (s.events.sutures.empty()) {
    throw Error(ErrorKind::Scenario, file + ": events: bench --materials needs a scenario with a suture event");
  }
  if (s.mesh.kind != MeshDef::Kind::Tet) {
    s.mesh.target_points = target_points;  // the same size as the material rows
    s.mesh.cell_size.reset();
    s.mesh.exude = options.exude;
  }
  const TetMesh mesh = load_scenario_mesh(s.mesh);
  const Model initial = build_scenario_model(s, mesh);
  double last_suture = 0;
  for (const SutureEvent& e : s.events.sutures) last_suture = std::max(last_suture, e.t);
  s.time.duration = last_suture + 2 * s.time.tick();
  s.time.settle = 0;
  s.outputs = OutputsDef{};
  s.outputs.forces = false;
  BackendSelection sel;  // on the CPU whatever the rows run on: only the Model versions count here
  sel.name = "cpu";
  sel.precision = options.precision;
  sel.threads = options.threads;
  auto backend = make_backend(sel, initial, backend_tool(s));
  SutureVersions versions;
  versions.unsutured = initial;
  RunOptions run;
  run.observers = {&versions};
  run_scenario(s, initial, *backend, run);
  if (!versions.sutured) {
    throw Error(ErrorKind::Scenario, file + ": events: no suture was tied by t = " +
                                         std::to_string(s.time.duration) + " s (nothing within max_distance?)");
  }
  return {std::move(*versions.unsutured), std::move(*versions.sutured)};
}

struct MaterialEntry {
  MaterialBenchRow row;
  const Model* model = nullptr;
  std::unique_ptr<Backend> backend;
  std::vector<double> ms;
};

}  // namespace

MaterialComparison measure_materials(const MaterialBenchOptions& options, const TetMesh& mesh,
                                     const std::string& mesh_name, int32_t target_points) {
  ModelOptions model_options;
  model_options.gravity = Vec3(0, 0, -9.81);  // as the size table: a moving model, no fixed points
  const Model per_tet = build_model(mesh, bench_material(-1), model_options, mesh_name);
  const Model nodal = build_model(mesh, bench_material(0.45), model_options, mesh_name);
  const Model shear = build_model(mesh, bench_material(0.2), model_options, mesh_name);
  if (!options.quiet) std::cerr << "bench: running " << options.suture_scenario.string() << " until its sutures\n";
  const auto [unsutured, sutured] = suture_models(options, target_points);
  const std::string scenario = options.suture_scenario.filename().string();

  std::vector<MaterialEntry> entries(5);
  entries[0].row.name = "volume_modulus";
  entries[0].row.material = "E 8 kPa, volume_modulus 20 kPa (per-tet volume term)";
  entries[0].model = &per_tet;
  entries[1].row.name = "nu_0.45";
  entries[1].row.material = "E 8 kPa, poisson_ratio 0.45 (averaged nodal volume term)";
  entries[1].model = &nodal;
  entries[2].row.name = "nu_0.2";
  entries[2].row.material = "E 8 kPa, poisson_ratio 0.2 (smoothed shear element)";
  entries[2].model = &shear;
  entries[3].row.name = "unsutured";
  entries[3].row.material = scenario + " after its cut, before the sutures";
  entries[3].model = &unsutured;
  entries[4].row.name = "sutured";
  entries[4].row.material = scenario + " after its cut, with the sutures";
  entries[4].model = &sutured;

  BackendSelection sel;
  sel.name = options.backend;
  sel.precision = options.precision;
  sel.threads = options.threads;
  std::vector<Vec3> positions;
  for (MaterialEntry& e : entries) {
    const Model& m = *e.model;
    e.row.points = m.npoint();
    e.row.springs = m.nspring();
    e.row.tets = m.ntet();
    e.row.sutures = m.nsuture();
    e.row.dt_crit = estimate_critical_step(m).dt_crit;
    e.row.dt = std::min(options.dt, 0.5 * e.row.dt_crit);
    e.backend = make_backend(sel, m, BackendTool{});
    for (const PassInfo& p : e.backend->plan().passes) e.row.passes.push_back(p.name);
    time_steps(*e.backend, options.steps.warmup, e.row.dt, positions);
    if (!options.quiet) std::cerr << "bench: " << e.row.name << ": " << m.npoint() << " points, dt " << e.row.dt << " s\n";
  }
  // Interleaved: every row sees the same stretch of machine load.
  for (int32_t r = 0; r < options.steps.repetitions; ++r) {
    for (MaterialEntry& e : entries) e.ms.push_back(time_steps(*e.backend, options.steps.steps, e.row.dt, positions));
  }

  MaterialComparison out;
  out.target_points = target_points;
  out.backend = options.backend;
  out.precision = options.precision;
  for (MaterialEntry& e : entries) {
    e.row.timing = summarise_ms(e.ms);
    e.row.device = e.backend->device();  // after the timing: the thread count and kernel it ran on
    e.row.kernel = options.backend == "cpu" ? kernel_of(e.row.device) : "glsl";
    out.rows.push_back(e.row);
  }
  auto ratio = [&](size_t of, size_t over, double target) {
    MaterialBenchRatio r;
    r.of = out.rows[of].name;
    r.over = out.rows[over].name;
    r.name = r.of + " / " + r.over;
    r.ratio = out.rows[of].timing.median_ms / out.rows[over].timing.median_ms;
    r.target = target;
    out.ratios.push_back(r);
  };
  ratio(1, 0, kNodalTarget);
  ratio(2, 0, kShearTarget);
  ratio(4, 3, kSutureTarget);
  return out;
}

nlohmann::json to_json(const MaterialComparison& c) {
  nlohmann::json j;
  j["target_points"] = c.target_points;
  j["backend"] = c.backend;
  j["precision"] = c.precision;
  j["rows"] = nlohmann::json::array();
  for (const MaterialBenchRow& r : c.rows) {
    j["rows"].push_back({{"name", r.name}, {"material", r.material}, {"points", r.points},
                         {"springs", r.springs}, {"tets", r.tets}, {"sutures", r.sutures},
                         {"dt", r.dt}, {"dt_crit", r.dt_crit}, {"device", r.device},
                         {"kernel", r.kernel}, {"passes", r.passes}, {"median_ms", r.timing.median_ms},
                         {"min_ms", r.timing.min_ms}, {"max_ms", r.timing.max_ms}});
  }
  j["ratios"] = nlohmann::json::array();
  for (const MaterialBenchRatio& r : c.ratios) {
    j["ratios"].push_back({{"name", r.name}, {"of", r.of}, {"over", r.over}, {"ratio", r.ratio},
                           {"target", r.target}, {"within_target", r.ratio <= r.target}});
  }
  return j;
}

void print_materials(std::ostream& out, const MaterialComparison& c) {
  out << "materials at " << c.target_points << " target points, " << c.backend << " " << c.precision << ", timed side by side (repetitions interleaved),"
      << " median (min..max) ms per step:\n";
  out << "  " << std::left << std::setw(15) << "row" << std::right << std::setw(7) << "points" << std::setw(8)
      << "springs" << std::setw(8) << "sutures" << std::setw(8) << "dt us" << "  " << std::left << std::setw(8)
      << "kernel" << std::right << std::setw(10) << "median ms" << std::setw(21) << "(min..max)" << "  material\n";
  for (const MaterialBenchRow& r : c.rows) {
    out << "  " << std::left << std::setw(15) << r.name << std::right << std::setw(7) << r.points << std::setw(8)
        << r.springs << std::setw(8) << r.sutures << std::setw(8) << fixed(1e6 * r.dt, 1) << "  " << std::left
        << std::setw(13) << r.kernel << std::right << std::setw(10) << fixed(r.timing.median_ms, 4) << std::setw(21)
        << ("(" + fixed(r.timing.min_ms, 4) + ".." + fixed(r.timing.max_ms, 4) + ")") << "  " << r.material
        << "\n";
  }
  out << "ratios of medians (aim: at or below the target):\n";
  for (const MaterialBenchRatio& r : c.ratios) {
    out << "  " << std::left << std::setw(28) << r.name << std::right << fixed(r.ratio, 2) << "x  (target "
        << fixed(r.target, 1) << "x: " << (r.ratio <= r.target ? "met" : "not met") << ")\n";
  }
  out << "devices:\n";
  for (const MaterialBenchRow& r : c.rows) out << "  " << r.name << ": " << r.device << "\n";
}

}  // namespace organsim::app
