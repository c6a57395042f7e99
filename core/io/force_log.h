#pragma once
// The force log: OUTDIR/forces.json, one sample per haptic tick.
//   {"meta": {...}, "samples": {"t": [...], "force": [[x,y,z], ...], "torque": [...],
//                               "tool_position": [...], "contacts": [...]}}
// and, for a grasper, "grip" (its jaws' closing forces summed, N) and
// "jaw_gap" (m).
// Columns rather than rows so that a reader loads each quantity as one array.
// Units: t s, force N, torque N m (about the tool centre), tool_position m.
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// Column storage, reserved once before a run so recording never allocates.
struct ForceSamples {
  std::vector<double> t;              // end of the tick, s (nsample)
  std::vector<Vec3> force;            // tool reaction, N (nsample)
  std::vector<Vec3> torque;           // about the tool centre, N m (nsample)
  std::vector<Vec3> tool_position;    // tool centre at the end of the tick, m (nsample)
  std::vector<int32_t> contacts;      // points in contact or attached (nsample)
  std::vector<double> grip;           // grasper: its jaws' closing forces summed, N (nsample, or empty)
  std::vector<double> jaw_gap;        // grasper: its jaws' gap, m (nsample, or empty)

  void reserve(size_t n);
  void push(double time, const Vec3& f, const Vec3& tq, const Vec3& tool, int32_t ncontact);
  size_t size() const { return t.size(); }
};

struct ForceLogMeta {
  std::string scenario;           // scenario file as given
  std::string backend;            // "cpu", "gl"
  std::string device;             // CPU model or GL renderer
  std::string precision;          // "double", "float"
  int32_t reaction_latency_ticks = 0;
  int32_t points = 0, springs = 0, tets = 0, fixed_points = 0;
  double dt = 0;                  // s
  int32_t substeps = 0;
  double duration = 0;            // s, as asked by the scenario
  double wall_seconds = 0;        // s, the stepping loop only
  double steps_per_second = 0;    // integration steps per wall-clock second
  // Simulated seconds per wall-clock second over the whole tick loop (checks,
  // frames and logging included): >= 1 keeps up with the clock.
  double real_time_factor = 0;
  bool completed = false;         // false when the run was cut short
  std::string stop_reason;        // why it was cut short; empty when completed
  // Anything other parts add (dt_crit, timings of meshing, renderer, ...).
  nlohmann::json extra = nlohmann::json::object();
};

nlohmann::json force_log_json(const ForceLogMeta& meta, const ForceSamples& samples);

// Writes the log atomically (temporary name + rename): either the complete
// file is there or, if anything throws, nothing under `path`.
void write_force_log(const std::filesystem::path& path, const ForceLogMeta& meta,
                     const ForceSamples& samples);

}  // namespace organsim
