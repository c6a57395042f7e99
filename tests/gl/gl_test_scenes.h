#pragma once
// Small box scenes shared by the GL tests (built from make_box_tet_mesh so
// the tests need neither CGAL nor the scenario files).
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/gl/gl_backend.h"
#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/sim/backend.h"
#include "core/sim/reference_backend.h"
#include "core/sim/reference_forces.h"
#include "core/run/run.h"
#include "core/sim/run_observer.h"
#include "tests/core/test_models.h"

namespace organsim::gl_test {

// A 0.1 x 0.1 x 0.05 m soft box (E = 3 kPa, liver-like), nx x ny x nz cubes.
// fixed_bottom: the z = 0 face is fixed. volume_modulus 0 turns the volume pass off.
inline Model box_model(int nx, int ny, int nz, bool fixed_bottom, double volume_modulus, const Vec3& gravity,
                       double viscous_damping = 1.0) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), nx, ny, nz);
  Material material;
  material.volume_modulus = volume_modulus;
  material.viscous_damping = viscous_damping;
  ModelOptions options;
  if (fixed_bottom) {
    options = testing::fixed_bottom_options(gravity);
  } else {
    options.gravity = gravity;
  }
  return build_model(mesh, material, options, "test box");
}

// The same box, 5 x 5 x 3 cubes, bottom fixed, with E = 3 kPa and a Poisson
// ratio (its volume term from 1/4 up, its shear element below), a damping
// time (the default Material's unless given), s, and the shear element's
// formulation (the default's unless given).
inline Model poisson_box(double nu, const Vec3& gravity, double spring_damping_time = Material{}.spring_damping_time,
                         ShearFormulation shear_formulation = Material{}.shear_formulation) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.05), 5, 5, 3);
  Material material;
  material.young_modulus = 3000;
  material.poisson_ratio = nu;
  material.spring_damping_time = spring_damping_time;
  material.shear_formulation = shear_formulation;
  return build_model(mesh, material, testing::fixed_bottom_options(gravity), "test box");
}

inline double bbox_diagonal(const Model& model) {
  Vec3 lo = model.rest_position[0], hi = lo;
  for (const Vec3& x : model.rest_position) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  return (hi - lo).norm();
}

// Positions rounded to float, as the GPU stores them: references evaluated
// at these see the same input, so only arithmetic differences remain.
inline std::vector<Vec3> round_to_float(const std::vector<Vec3>& x) {
  std::vector<Vec3> r(x.size());
  for (size_t i = 0; i < x.size(); ++i) r[i] = x[i].cast<float>().cast<double>();
  return r;
}

// Rest positions displaced by uniform noise of +-amplitude per coordinate, m.
inline std::vector<Vec3> perturbed(const Model& model, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p += Vec3(u(rng), u(rng), u(rng));
  return round_to_float(x);
}

// The free points of a box on its base moved 2 % towards its base's centre
// (0.05, 0.05, 0), rounded to float: a uniform squeeze that springs back
// within the first ~10 ms, so every pressure and stiffness term drives the
// motion.
inline std::vector<Vec3> squeezed_box(const Model& model) {
  std::vector<Vec3> squeezed = model.rest_position;
  const Vec3 centre(0.05, 0.05, 0.0);
  for (int32_t i = 0; i < model.npoint(); ++i)
    if (!model.fixed[i]) squeezed[i] = centre + 0.98 * (squeezed[i] - centre);
  return round_to_float(squeezed);
}

// A deformed state with velocities: x_t noisy by 1 mm, x_{t-1} by another
// 1 um, both rounded to float; v = (x_t - x_{t-1}) / dt as the kernels see it.
struct MovingState {
  std::vector<Vec3> x, x_prev, v;
};
inline MovingState moving_state(const Model& model, double dt, unsigned seed = 7) {
  MovingState s;
  s.x = perturbed(model, 1e-3, seed);
  s.x_prev = s.x;
  std::mt19937 rng(seed + 4);
  std::uniform_real_distribution<double> u(-1e-6, 1e-6);
  for (Vec3& p : s.x_prev) p += Vec3(u(rng), u(rng), u(rng));
  s.x_prev = round_to_float(s.x_prev);
  s.v.resize(s.x.size());
  for (size_t i = 0; i < s.x.size(); ++i) s.v[i] = (s.x[i] - s.x_prev[i]) / dt;
  return s;
}

// Starts `gl` (built with record_forces) from `state`, runs one substep of dt
// and returns the force on every point that step used.
inline std::vector<Vec3> forces_of_one_substep(GlBackend& gl, const MovingState& state, double dt) {
  gl.set_state(state.x, state.x_prev);
  TickRequest request;
  request.dt = dt;
  request.substeps = 1;
  gl.tick(request);
  std::vector<Vec3> f;
  gl.forces(f);
  return f;
}

// forces_of_one_substep on `gl` (running `model`) against the double
// reference force: max |f_gl - f_ref| / max |f_ref|.
inline double substep_force_error(GlBackend& gl, const Model& model, const MovingState& s, double dt) {
  const std::vector<Vec3> got = forces_of_one_substep(gl, s, dt);
  std::vector<Vec3> want;
  reference_internal_forces(model, s.x, s.v, want);
  double worst = 0, largest = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    worst = std::max(worst, (got[i] - want[i]).norm());
    largest = std::max(largest, want[i].norm());
  }
  return worst / largest;
}

// One GL substep of dt from state `s` (with `threads_per_point` invocations
// per point) against the double reference force: max |f_gl - f_ref| / max |f_ref|.
inline double one_substep_force_error(const Model& model, const MovingState& s, double dt,
                                      int32_t threads_per_point = 1) {
  GlBackendOptions options;
  options.record_forces = true;
  options.threads_per_point = threads_per_point;
  GlBackend gl(model, BackendTool{}, options);
  return substep_force_error(gl, model, s, dt);
}

// `ticks` ticks of 10 substeps of dt from `start` (at rest) on a double
// reference and on GL, compared after every tick: the largest position
// difference and the reference's largest motion from start, m. The
// reference is `reference_tick(request, x)`: one tick, then its positions in x.
struct TrajectoryDifference {
  double worst = 0, motion = 0;
};
template <class ReferenceTick>
inline TrajectoryDifference reference_and_gl_from(const Model& model, const std::vector<Vec3>& start, double dt,
                                                  int ticks, ReferenceTick&& reference_tick) {
  GlBackend gl(model, BackendTool{}, {});
  gl.set_state(start, start);
  TickRequest request;
  request.dt = dt;
  request.substeps = 10;
  TrajectoryDifference d;
  std::vector<Vec3> xc, xg;
  for (int n = 0; n < ticks; ++n) {
    reference_tick(request, xc);
    gl.tick(request);
    gl.positions(xg);
    for (size_t i = 0; i < xc.size(); ++i) {
      d.worst = std::max(d.worst, (xg[i] - xc[i]).norm());
      d.motion = std::max(d.motion, (xc[i] - start[i]).norm());
    }
  }
  return d;
}

// reference_and_gl_from with the double CPU backend as the reference.
inline TrajectoryDifference cpu_and_gl_from(const Model& model, const std::vector<Vec3>& start, double dt, int ticks) {
  auto cpu = make_reference_backend(model, {}, Integrator::Verlet);
  cpu->set_state(start, start);
  return reference_and_gl_from(model, start, dt, ticks, [&](const TickRequest& request, std::vector<Vec3>& x) {
    cpu->tick(request);
    cpu->positions(x);
  });
}

// Counts a run's topology changes and keeps its final positions.
struct FinalState final : RunObserver {
  std::vector<Vec3> x;
  int changes = 0;
  void on_tick(const Model&, Backend&, const TickInfo&) override {}
  void on_topology_changed(const Model&, Backend&) override { ++changes; }
  void on_finish(const Model&, Backend& backend) override { backend.positions(x); }
};

// The same scenario run on the double CPU reference (one thread) and on GL
// (with `threads_per_point` invocations per point, 0: the backend's
// default), each observed by a FinalState; outputs under
// ORGANSIM_TEST_TMP/name_{cpu,gl}.
struct CpuAndGlRuns {
  RunResult cpu, gl;
  FinalState cpu_end, gl_end;
  int32_t gl_latency = 0;  // GlBackend::reaction_latency_ticks()
  // max_i |x_gl - x_cpu| at the end, divided by `scale`.
  double worst_position_difference(double scale) const {
    double worst = 0;
    for (size_t i = 0; i < cpu_end.x.size(); ++i) worst = std::max(worst, (gl_end.x[i] - cpu_end.x[i]).norm());
    return worst / scale;
  }
};
inline CpuAndGlRuns run_on_cpu_and_gl(const Scenario& s, const Model& model, const std::string& name,
                                      int32_t threads_per_point = 0) {
  CpuAndGlRuns r;
  auto cpu = make_reference_backend(model, backend_tool(s), Integrator::Verlet);
  GlBackendOptions gl_options;
  gl_options.threads_per_point = threads_per_point;
  GlBackend gl(model, backend_tool(s), gl_options);
  r.gl_latency = gl.reaction_latency_ticks();
  RunOptions options;
  options.outdir = std::filesystem::path(ORGANSIM_TEST_TMP) / (name + "_cpu");
  options.observers = {&r.cpu_end};
  r.cpu = run_scenario(s, model, *cpu, options);
  options.outdir = std::filesystem::path(ORGANSIM_TEST_TMP) / (name + "_gl");
  options.observers = {&r.gl_end};
  r.gl = run_scenario(s, model, gl, options);
  return r;
}

}  // namespace organsim::gl_test
