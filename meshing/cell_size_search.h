#pragma once
// The search for the cell size that gives a target point count, shared by
// surfaces and labelled images: secant steps on (log h, log N) from the
// first guess N ~ V / h^3. Deterministic: the same domain and target give
// the same h.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace organsim {

// Absurd cell sizes are refused before Mesh_3 runs for hours: a domain of
// V m^3 meshed at cell size h gets roughly V / h^3 points, and surfaces and
// images alike refuse an estimate above this.
inline constexpr double kMaxEstimatedPoints = 5e7;

// `points_at(h)` meshes at cell size h (quickly: no exudation) and returns
// the point count. Returns the h whose count is closest to `target`; adds a
// note; throws Error(Input) naming `source` when no try is within 10 %.
// `on_try` (may be empty) hears "try 2 of at most 10, cell size 0.004 m".
double search_cell_size(const std::function<int32_t(double)>& points_at, double volume, int32_t target,
                        const std::function<void(const std::string&)>& on_try, const std::string& source,
                        std::vector<std::string>& notes);

}  // namespace organsim
