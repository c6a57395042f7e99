#pragma once
// `organsim bench --implicit`: what a step of each integrator costs, side
// by side in one run on the bench's liver hung by its top (the points in
// the top tenth of its height fixed), sagging under gravity with a 2 cm
// sphere pressed 5 mm into its lowest point. Rows, repetitions
// interleaved: the soft liver (E 8 kPa, poisson_ratio 0.45) under Verlet
// on the CPU backend (double) at its guaranteed step (as `organsim run`
// steps it) and under implicit Euler at 1 ms, the same for a stiff liver
// (E 1 MPa), the stiff liver under implicit damping at the largest step
// that divides 1 ms within its undamped limit and under implicit Euler with
// the two-level preconditioner, and the soft liver's implicit Euler once
// more on the scalar product (the reference gather; the others gather on
// the kernel's SIMD target). Each row gives ms per
// step and per simulated ms; the implicit rows also CG iterations per step
// and ms per CG iteration (the backend's own timer around its solves, over
// the timed steps), so that one CG iteration is compared with one explicit
// step in the same run.
#include <nlohmann/json.hpp>

#include <iosfwd>
#include <string>
#include <vector>

#include "app/bench_timing.h"
#include "core/mesh/tet_mesh.h"

namespace organsim::app {

struct ImplicitBenchOptions {
  int32_t threads = 1;  // every row's
  BenchSteps steps;
  double implicit_dt = 1e-3;  // s: one haptic tick
  bool quiet = false;         // no progress lines on stderr
};

struct ImplicitBenchRow {
  std::string name;        // "verlet_8kPa", "implicit_8kPa", ..., "two_level_1MPa", "scalar_8kPa"
  std::string material;    // in words
  std::string integrator;  // "verlet" | "implicit_euler" | "implicit_damping"
  int32_t points = 0, fixed = 0;
  double dt = 0, dt_crit = 0;  // s
  std::string device;
  BenchTiming timing;               // ms per step
  double ms_per_simulated_ms = 0;   // median ms per step / dt in ms (1: real time)
  double cg_iterations_median = 0;  // implicit: per timed step
  double cg_ms_per_iteration = 0;   // implicit: solve time over iterations, timed steps
};

struct ImplicitBenchRatio {
  std::string name, what;
  double value = 0, target = 0;  // aim: value at or below target
};

struct ImplicitComparison {
  int32_t target_points = 0;
  std::vector<ImplicitBenchRow> rows;
  std::vector<ImplicitBenchRatio> ratios;
};

// Builds the soft and the stiff liver on `mesh` (the bench's liver at
// `target_points`), warms each row up, then times the rows with their
// repetitions interleaved (row 1, 2, ..., 7, row 1, ...).
ImplicitComparison measure_implicit(const ImplicitBenchOptions& options, const TetMesh& mesh,
                                    const std::string& mesh_name, int32_t target_points);

nlohmann::json to_json(const ImplicitComparison& comparison);
void print_implicit(std::ostream& out, const ImplicitComparison& comparison);

}  // namespace organsim::app
