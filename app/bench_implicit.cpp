#include "app/bench_implicit.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/backend_factory.h"
#include "core/model/model.h"
#include "core/sim/reference_backend.h"
#include "core/stability/critical_step.h"

namespace organsim::app {
namespace {

// The aims (docs/integrators.md): a CG iteration at most 1.5 explicit
// steps, at most 30 of them per 1 ms step of the soft liver, and the stiff
// liver under implicit Euler in a third of Verlet's wall time per simulated ms
// (with the default block Jacobi and with the two-level preconditioner); the
// SIMD product no slower than the scalar one.
constexpr double kCgIterationTarget = 1.5;
constexpr double kSoftIterationsTarget = 30;
constexpr double kStiffWallTarget = 1.0 / 3;

// The bench's tool (cmd_bench.cpp --tool surface): a 2 cm sphere on the
// surface with its sub-cell layer, 500 N/m, pressed 5 mm into the lowest point.
constexpr double kToolRadius = 0.02, kToolDepth = 0.005;
BackendTool bench_sphere() {
  BackendTool tool{true, ToolMode::Push, kToolRadius, 500.0, ToolContact::Surface};
  tool.hertz_layer = true;
  return tool;
}

Model hung_liver(const TetMesh& mesh, double young_modulus, const std::string& mesh_name) {
  Material material;  // scenarios/liver7750_realtime.json's, at young_modulus
  material.young_modulus = young_modulus;
  material.poisson_ratio = 0.45;
  material.spring_damping_time = 0.0005;
  material.viscous_damping = 5;
  ModelOptions options;
  options.gravity = Vec3(0, 0, -9.81);
  double zmin = mesh.points.front().z(), zmax = zmin;
  for (const Vec3& p : mesh.points) zmin = std::min(zmin, p.z()), zmax = std::max(zmax, p.z());
  FixedSelector top;
  top.kind = FixedSelector::Kind::Plane;
  top.point = Vec3(0, 0, zmax - 0.1 * (zmax - zmin));
  top.normal = Vec3(0, 0, 1);
  options.fixed = {top};
  return build_model(mesh, material, options, mesh_name);
}

struct ImplicitEntry {
  ImplicitBenchRow row;
  const Model* model = nullptr;
  std::unique_ptr<Backend> backend;
  BenchSteps steps;
  std::vector<Vec3> positions;  // the row's own: they place its tool
  std::vector<double> ms;
  int64_t first_timed_step = 0;
  double cg_seconds_before = 0;
};

}  // namespace

ImplicitComparison measure_implicit(const ImplicitBenchOptions& options, const TetMesh& mesh,
                                    const std::string& mesh_name, int32_t target_points) {
  const Model soft = hung_liver(mesh, 8000, mesh_name), stiff = hung_liver(mesh, 1e6, mesh_name);
  // An implicit step costs tens of explicit ones: a tenth of the steps.
  BenchSteps implicit_steps = options.steps;
  implicit_steps.warmup = (options.steps.warmup + 9) / 10;
  implicit_steps.steps = (options.steps.steps + 9) / 10;
  std::vector<ImplicitEntry> entries(7);
  const auto set = [&](ImplicitEntry& e, const char* name, const char* material, const Model& m, Integrator integrator,
                       Preconditioner preconditioner = Preconditioner::BlockJacobi, bool scalar_product = false) {
    e.row.name = name;
    e.row.material = material;
    e.row.integrator = integrator_name(integrator);
    e.model = &m;
    e.row.points = m.npoint();
    e.row.fixed = static_cast<int32_t>(std::count(m.fixed.begin(), m.fixed.end(), 1));
    const StabilityReport stability = estimate_critical_step(m);
    e.row.dt_crit = stability.dt_crit;
    const bool implicit = integrator != Integrator::Verlet;
    // Verlet at the guaranteed step, as `organsim run` would step it;
    // implicit Euler at the haptic tick; implicit damping at the largest
    // step that divides the tick within the undamped limit it is held to.
    if (integrator == Integrator::Verlet)
      e.row.dt = stability.dt_crit_gershgorin;
    else if (integrator == Integrator::ImplicitDamping)
      e.row.dt = options.implicit_dt / std::ceil(options.implicit_dt / stability.dt_crit_undamped);
    else
      e.row.dt = options.implicit_dt;
    e.steps = implicit ? implicit_steps : options.steps;
    BackendSelection sel;
    sel.name = "cpu";
    sel.precision = "double";
    sel.threads = options.threads;
    sel.integrator = integrator;
    sel.implicit.preconditioner = preconditioner;
    // The backend's products gather on the kernel's SIMD target; the scalar
    // gather (the reference, ImplicitOptions without simd_product) beside it.
    e.backend = scalar_product ? make_reference_backend(m, bench_sphere(), integrator, sel.implicit, options.threads)
                               : make_backend(sel, m, bench_sphere());
  };
  set(entries[0], "verlet_8kPa", "E 8 kPa, poisson_ratio 0.45", soft, Integrator::Verlet);
  set(entries[1], "implicit_8kPa", "E 8 kPa, poisson_ratio 0.45", soft, Integrator::ImplicitEuler);
  set(entries[2], "verlet_1MPa", "E 1 MPa, poisson_ratio 0.45", stiff, Integrator::Verlet);
  set(entries[3], "implicit_1MPa", "E 1 MPa, poisson_ratio 0.45", stiff, Integrator::ImplicitEuler);
  set(entries[4], "damping_1MPa", "E 1 MPa, poisson_ratio 0.45", stiff, Integrator::ImplicitDamping);
  set(entries[5], "two_level_1MPa", "E 1 MPa, poisson_ratio 0.45", stiff, Integrator::ImplicitEuler,
      Preconditioner::TwoLevel);
  set(entries[6], "scalar_8kPa", "E 8 kPa, poisson_ratio 0.45", soft, Integrator::ImplicitEuler,
      Preconditioner::BlockJacobi, true);
  const BenchToolPlacement tool{kToolRadius, kToolDepth};
  for (ImplicitEntry& e : entries) {
    if (!options.quiet)
      std::cerr << "bench: " << e.row.name << ": " << e.row.points << " points (" << e.row.fixed << " fixed), dt "
                << e.row.dt << " s\n";
    time_steps(*e.backend, e.steps.warmup, e.row.dt, e.positions, tool);
    if (const IntegratorStats* stats = e.backend->integrator_stats()) {
      e.first_timed_step = stats->steps();
      e.cg_seconds_before = stats->cg_seconds;
    }
  }
  // Interleaved: every row sees the same stretch of machine load.
  for (int32_t r = 0; r < options.steps.repetitions; ++r)
    for (ImplicitEntry& e : entries) e.ms.push_back(time_steps(*e.backend, e.steps.steps, e.row.dt, e.positions, tool));

  ImplicitComparison out;
  out.target_points = target_points;
  for (ImplicitEntry& e : entries) {
    e.row.timing = summarise_ms(e.ms);
    e.row.ms_per_simulated_ms = e.row.timing.median_ms / (1e3 * e.row.dt);
    e.row.device = e.backend->device();
    if (const IntegratorStats* stats = e.backend->integrator_stats()) {
      std::vector<double> iterations(stats->cg_iterations.begin() + e.first_timed_step, stats->cg_iterations.end());
      double total = 0;
      for (double i : iterations) total += i;
      e.row.cg_iterations_median = summarise_ms(iterations).median_ms;
      e.row.cg_ms_per_iteration = total > 0 ? 1e3 * (stats->cg_seconds - e.cg_seconds_before) / total : 0;
    }
    out.rows.push_back(e.row);
  }
  const std::vector<ImplicitBenchRow>& r = out.rows;
  out.ratios.push_back({"cg_iteration / verlet_step", "ms per CG iteration (implicit_8kPa) over ms per Verlet step (verlet_8kPa)",
                        r[1].cg_ms_per_iteration / r[0].timing.median_ms, kCgIterationTarget});
  out.ratios.push_back({"cg_iterations_8kPa", "CG iterations per 1 ms step of the soft liver (median)",
                        r[1].cg_iterations_median, kSoftIterationsTarget});
  out.ratios.push_back({"implicit_1MPa / verlet_1MPa", "wall time per simulated ms, implicit Euler over Verlet, stiff liver",
                        r[3].ms_per_simulated_ms / r[2].ms_per_simulated_ms, kStiffWallTarget});
  out.ratios.push_back({"two_level_1MPa / verlet_1MPa",
                        "the same with the two-level preconditioner (block Jacobi and a coarse correction)",
                        r[5].ms_per_simulated_ms / r[2].ms_per_simulated_ms, kStiffWallTarget});
  out.ratios.push_back({"simd_product / scalar_product",
                        "ms per CG iteration (implicit_8kPa) over the same on the scalar gather (scalar_8kPa)",
                        r[1].cg_ms_per_iteration / r[6].cg_ms_per_iteration, 1.0});
  return out;
}

nlohmann::json to_json(const ImplicitComparison& c) {
  nlohmann::json j;
  j["target_points"] = c.target_points;
  j["rows"] = nlohmann::json::array();
  for (const ImplicitBenchRow& r : c.rows)
    j["rows"].push_back({{"name", r.name}, {"material", r.material}, {"integrator", r.integrator},
                         {"points", r.points}, {"fixed", r.fixed}, {"dt", r.dt}, {"dt_crit", r.dt_crit},
                         {"device", r.device}, {"median_ms", r.timing.median_ms}, {"min_ms", r.timing.min_ms},
                         {"max_ms", r.timing.max_ms}, {"ms_per_simulated_ms", r.ms_per_simulated_ms},
                         {"cg_iterations_median", r.cg_iterations_median},
                         {"cg_ms_per_iteration", r.cg_ms_per_iteration}});
  j["ratios"] = nlohmann::json::array();
  for (const ImplicitBenchRatio& r : c.ratios)
    j["ratios"].push_back({{"name", r.name}, {"what", r.what}, {"value", r.value}, {"target", r.target},
                           {"within_target", r.value <= r.target}});
  return j;
}

void print_implicit(std::ostream& out, const ImplicitComparison& c) {
  out << "integrators at " << c.target_points << " target points, cpu double, timed side by side (repetitions "
      << "interleaved), median (min..max) ms per step:\n";
  out << "  " << std::left << std::setw(15) << "row" << std::right << std::setw(7) << "points" << std::setw(10)
      << "dt us" << std::setw(10) << "median ms" << std::setw(21) << "(min..max)" << std::setw(14) << "ms/sim ms"
      << std::setw(8) << "CG it" << std::setw(12) << "ms/CG it" << "  material\n";
  for (const ImplicitBenchRow& r : c.rows) {
    const bool implicit = r.integrator != "verlet";
    std::ostringstream range;
    range << std::fixed << std::setprecision(4) << "(" << r.timing.min_ms << ".." << r.timing.max_ms << ")";
    const std::string iterations = implicit ? fixed(r.cg_iterations_median, 1) : std::string("-");
    const std::string per_iteration = implicit ? fixed(r.cg_ms_per_iteration, 4) : std::string("-");
    out << "  " << std::left << std::setw(15) << r.name << std::right << std::setw(7) << r.points << std::setw(10)
        << fixed(1e6 * r.dt, 2) << std::setw(10) << fixed(r.timing.median_ms, 4) << std::setw(21)
        << range.str() << std::setw(14) << fixed(r.ms_per_simulated_ms, 3) << std::setw(8) << iterations << std::setw(12)
        << per_iteration << "  " << r.material << "\n";
  }
  out << "aims (at or below the target):\n";
  for (const ImplicitBenchRatio& r : c.ratios)
    out << "  " << std::left << std::setw(30) << r.name << std::right << std::setw(8) << fixed(r.value, 2)
        << "  (target " << fixed(r.target, 2) << ": " << (r.value <= r.target ? "met" : "not met") << ")  " << r.what
        << "\n";
  out << "devices:\n";
  for (const ImplicitBenchRow& r : c.rows) out << "  " << r.name << ": " << r.device << "\n";
}

}  // namespace organsim::app
