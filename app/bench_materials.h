#pragma once
// `organsim bench --materials`: what the materials cost per step, side by
// side in one run on one mesh size, so that machine load is shared by every
// row instead of differing between runs. Rows: the old per-tet
// `volume_modulus` material, poisson_ratio 0.45 (the averaged nodal volume
// term), poisson_ratio 0.2 (the smoothed shear element), and a scenario with
// sutures (scenarios/liver_suture.json) before and after they are tied, on
// the CPU backend (each row names the kernel it ran on) or the GL backend.
// The ratios are of medians.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "app/bench_timing.h"
#include "core/mesh/tet_mesh.h"

namespace organsim::app {

struct MaterialBenchOptions {
  std::string backend = "cpu";  // or "gl"
  std::string precision = "float";
  int32_t threads = 0;  // 0: the backend's choice
  BenchSteps steps;
  double dt = 1e-4;     // s, at most; half a model's dt_crit if smaller
  bool exude = true;    // meshing the scenario's surface
  std::filesystem::path suture_scenario = "scenarios/liver_suture.json";
  bool quiet = false;   // no progress lines on stderr
};

struct MaterialBenchRow {
  std::string name;      // short key: "volume_modulus", "nu_0.45", "nu_0.2", "unsutured", "sutured"
  std::string material;  // what the model is, in words
  int32_t points = 0, springs = 0, tets = 0, sutures = 0;
  double dt = 0, dt_crit = 0;  // s
  std::string device;    // the backend's device line after the timing
  std::string kernel;    // "simd (avx2)", ...: the CPU kernel this row ran on; "glsl" on gl
  std::vector<std::string> passes;
  BenchTiming timing;
};

struct MaterialBenchRatio {
  std::string name;        // e.g. "nu_0.45 / volume_modulus"
  std::string of, over;    // row names
  double ratio = 0;        // median of `of` over median of `over`
  double target = 0;       // the aim (docs/bench.md): ratio at or below it
};

struct MaterialComparison {
  int32_t target_points = 0;
  std::string backend;    // of every row
  std::string precision;  // of every row
  std::vector<MaterialBenchRow> rows;
  std::vector<MaterialBenchRatio> ratios;
};

// Builds the three material models on `mesh` (the bench's liver at
// `target_points`), and the suture scenario's model meshed to the same
// target, runs that scenario's events until its sutures are tied, then times
// all five rows with their repetitions interleaved (row 1, 2, ..., 5, row 1,
// ...). Throws Error(Scenario) for a scenario without sutures.
MaterialComparison measure_materials(const MaterialBenchOptions& options, const TetMesh& mesh,
                                     const std::string& mesh_name, int32_t target_points);

nlohmann::json to_json(const MaterialComparison& comparison);
void print_materials(std::ostream& out, const MaterialComparison& comparison);

}  // namespace organsim::app
