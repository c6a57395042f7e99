#pragma once
// What a run reports of its integrator: the force log's meta.integrator and
// the implicit solver's warning (core/sim/reference_backend.h).
#include <nlohmann/json.hpp>

#include <string>

#include "core/sim/backend.h"

namespace organsim {

// {"name": "verlet"} or, for implicit Euler, its solver's settings and what
// the solves did: CG iterations per step (median, max), the largest final
// relative residual, the steps whose CG stopped at cg_max_iterations above
// its tolerance and the steps whose state swung back (count and share of
// each: IntegratorStats).
nlohmann::json integrator_meta(const Backend& backend);

// Share of steps above which a run's exit status says its solves fell short.
inline constexpr double kUnconvergedShareWarning = 0.01;

// "" while the implicit solver converged, and the state did not alternate,
// in all but at most 1 % of the steps (or the integrator is explicit); else
// the warning, naming the counts.
std::string integrator_warning(const Backend& backend);

// The summary line a command prints after an implicit run, from its
// integrator_meta(): "CG iterations per step median M, max X; largest
// final residual R; N steps stopped at cg_max_iterations; A alternating";
// "" for Verlet.
std::string integrator_summary(const nlohmann::json& meta);

// "CG at its limit in N of M steps", "alternating in N of M steps" (or
// both) for the progress line; "" when neither happened.
std::string integrator_progress(const Backend& backend);

}  // namespace organsim
