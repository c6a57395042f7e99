#include "core/run/settle.h"

#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/sim/cpu_backend.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {

// Largest net force on a free point with zero velocity (springs, volume, gravity).
double residual_force(const Model& model, const std::vector<Vec3>& x, std::vector<Vec3>& force) {
  const std::vector<Vec3> v(x.size(), Vec3::Zero());
  reference_internal_forces(model, x, v, force);
  double largest = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!model.fixed[i]) largest = std::max(largest, force[i].norm());
  }
  return largest;
}

}  // namespace

SettleResult settle(const Model& model, const SettleOptions& options) {
  if (!(options.seconds > 0)) throw Error(ErrorKind::Scenario, "time.settle: expected a time > 0 s");
  const auto start = std::chrono::steady_clock::now();
  CpuBackendOptions cpu;
  cpu.precision = Precision::Double;
  cpu.threads = options.threads;
  const auto backend = solves_implicitly(options.integrator)
                           ? make_reference_backend(model, BackendTool{}, options.integrator, options.implicit)
                           : make_cpu_backend(model, BackendTool{}, cpu);

  double heaviest_weight = 0;
  for (int32_t i = 0; i < model.npoint(); ++i) heaviest_weight = std::max(heaviest_weight, model.mass[i] * model.gravity.norm());
  const double tick = options.dt * options.substeps;
  const auto max_ticks = static_cast<int64_t>(std::ceil(options.seconds / tick - 1e-9));

  TickRequest request;
  request.dt = options.dt;
  request.substeps = options.substeps;
  std::vector<Vec3> x, last, force;
  backend->positions(last);
  SettleResult r;
  double previous_energy = 0;
  for (r.ticks = 0; r.ticks < max_ticks;) {
    backend->tick(request);
    ++r.ticks;
    backend->positions(x);
    double energy = 0;
    for (size_t i = 0; i < x.size(); ++i) energy += 0.5 * model.mass[i] * (x[i] - last[i]).squaredNorm() / (tick * tick);
    if (energy < previous_energy) {
      backend->set_state(x, x);  // past the peak: take the kinetic energy out
      previous_energy = 0;
    } else {
      previous_energy = energy;
    }
    std::swap(x, last);
    // Checking costs about one step; every 10 ticks keeps it near 1 %.
    if (r.ticks % 10 == 0 && heaviest_weight > 0 &&
        residual_force(model, last, force) < options.tolerance * heaviest_weight) {
      r.converged = true;
      break;
    }
  }
  r.positions = std::move(last);
  r.seconds = static_cast<double>(r.ticks) * tick;
  r.residual_force = residual_force(model, r.positions, force);
  r.residual_relative = heaviest_weight > 0 ? r.residual_force / heaviest_weight : 0;
  if (heaviest_weight == 0) r.converged = r.residual_force == 0;
  for (int32_t i = 0; i < model.npoint(); ++i) {
    r.max_displacement = std::max(r.max_displacement, (r.positions[i] - model.rest_position[i]).norm());
  }
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

std::string describe(const SettleResult& r) {
  return format_number(r.seconds) + " s (" + std::to_string(r.ticks) + " ticks, " + format_number(r.wall_seconds, "%.2f") +
         " s wall): sag " + format_number(r.max_displacement) + " m, residual force " + format_number(r.residual_force) +
         " N = " + format_number(r.residual_relative) + " of the heaviest point's weight" +
         (r.converged ? "" : " (not converged: raise time.settle)");
}

nlohmann::json to_json(const SettleResult& r) {
  return {{"seconds", r.seconds},
          {"ticks", r.ticks},
          {"converged", r.converged},
          {"residual_force_N", r.residual_force},
          {"residual_relative", r.residual_relative},
          {"max_displacement_m", r.max_displacement},
          {"wall_seconds", r.wall_seconds}};
}

}  // namespace organsim
