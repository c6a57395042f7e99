#pragma once
// The scenario's `events` section: topology changes during a run (cuts,
// tears, sutures). Parsed and validated by parse_scenario(); applied between
// ticks by the run loop (core/topology/). Documented field by field in
// docs/scenarios.md. SI units.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

// A blade: the straight cutting edge from `a` to `b` at time `t`.
struct BladeKeyframe {
  double t = 0;      // s
  Vec3 a{0, 0, 0};   // m
  Vec3 b{0, 0, 0};   // m
};

// `cut`: the blade moves through its keyframes (linear interpolation); the
// material separates where it sweeps between the first and the last.
struct CutEvent {
  std::string name;                     // for sutures along it and the log
  std::vector<BladeKeyframe> keyframes;  // sorted by strictly increasing t, at least two
  // Off the tick's path: the Model version this cut makes is built on a
  // worker thread while the run steps the previous one, and swapped in at
  // the first tick that starts at or after `applied_at` (s; what `organsim
  // serve` records for a client's cut, two keyframes one tick apart).
  std::optional<double> applied_at;
  // Off the tick's path, swapped in at the first tick after the worker is
  // done (a live client's cut; the run tells its ToolDriver that tick).
  bool when_ready = false;

  double start() const { return keyframes.front().t; }
  double end() const { return keyframes.back().t; }
  // Blade ends at time t, clamped to the keyframes' span.
  void blade_at(double t, Vec3& a, Vec3& b) const;
};

// `tear`: from `start` on, springs strained past `strain` for `ticks`
// consecutive ticks separate a face; at most `max_per_tick` faces per tick.
struct TearEvent {
  double start = 0;            // s
  double strain = 0.5;         // (L - r) / r, dimensionless
  int32_t ticks = 3;
  int32_t max_per_tick = 4;
};

// `suture`: at the first tick starting at or after `t`, tension-only springs
// (core/model/suture.h) join either the given point pairs or, along the
// named cut, points on its two sides. See docs/scenarios.md#suture.
struct SutureEvent {
  std::string where;  // "FILE: events[i].suture", the prefix of errors found during the run
  double t = 0;                                // s
  double stiffness = 0;                        // N/m per suture (before the light-point scaling)
  std::vector<std::array<int32_t, 2>> pairs;   // output numbering; empty when `along` is set
  std::string along;                           // a cut's name
  double spacing = 0;                          // m, between sutures along the cut
  double max_distance = 0;                     // m, from a point to its partner across the cut
  std::optional<double> length;                // rest length when tied, m; default: the current distance
  double rate = 0;                             // tightening, m/s
  double min_length = 0;                       // m

  // Rest length of a suture tied now across `distance` (m).
  double tied_length(double distance) const { return length ? *length : distance; }
};

struct EventsDef {
  std::vector<CutEvent> cuts;
  std::optional<TearEvent> tear;
  std::vector<SutureEvent> sutures;  // in the order given

  bool any() const { return !cuts.empty() || tear.has_value() || !sutures.empty(); }
};

}  // namespace organsim
