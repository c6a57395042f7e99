// The cell-size search for a target point count (see cell_size_search.h).
#include "meshing/cell_size_search.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/util/error.h"
#include "core/util/format.h"

namespace organsim {

namespace {
// The point count N of a Mesh_3 mesh falls roughly like h^-3 with the cell
// size h (more slowly for coarse meshes, where surface points dominate).
// Start from N ~ kPointsPerVolume * V / h^3, then secant steps on
// (log h, log N).
constexpr double kPointsPerVolume = 1.0;   // first guess only; corrected by the iteration
constexpr double kAcceptTolerance = 0.03;  // stop when within 3 % (the promise is 10 %)
constexpr int kMaxTries = 10;

struct Try {
  double h;
  int32_t points;
};
}  // namespace

double search_cell_size(const std::function<int32_t(double)>& points_at, double volume, int32_t target,
                        const std::function<void(const std::string&)>& on_try, const std::string& source,
                        std::vector<std::string>& notes) {
  std::vector<Try> tries;
  double h = std::cbrt(kPointsPerVolume * volume / target);
  for (int i = 0; i < kMaxTries; ++i) {
    if (on_try) {
      on_try("searching the cell size for " + std::to_string(target) + " points: try " + std::to_string(i + 1) +
             " of at most " + std::to_string(kMaxTries) + ", cell size " + format_number(h) + " m");
    }
    tries.push_back({h, points_at(h)});
    const double error = std::log(static_cast<double>(std::max(tries.back().points, 1)) / target);
    if (std::abs(error) < std::log1p(kAcceptTolerance)) break;
    double slope = -3.0;
    if (tries.size() >= 2) {
      const Try& a = tries[tries.size() - 2];
      const Try& b = tries.back();
      if (a.h != b.h && a.points != b.points && a.points > 0 && b.points > 0) {
        slope = (std::log(double(b.points)) - std::log(double(a.points))) / (std::log(b.h) - std::log(a.h));
      }
      slope = std::clamp(slope, -4.0, -1.0);
    }
    // Never jump by more than a factor 2 in one step.
    const double step = std::clamp(-error / slope, -std::log(2.0), std::log(2.0));
    h *= std::exp(step);
  }
  const auto miss = [&](const Try& t) { return std::abs(std::log(double(std::max(t.points, 1)) / target)); };
  const Try best = *std::min_element(tries.begin(), tries.end(), [&](const Try& a, const Try& b) { return miss(a) < miss(b); });
  std::ostringstream note;
  note << "target " << target << " points: cell size " << format_number(best.h) << " m after " << tries.size()
       << " tries (" << best.points << " points)";
  notes.push_back(note.str());
  if (std::abs(best.points - target) > 0.1 * target) {
    throw input_error(source, "cannot reach " + std::to_string(target) + " points within 10 %: closest was " +
                                  std::to_string(best.points) + " at cell size " + format_number(best.h) +
                                  " m; give --cell-size instead");
  }
  return best.h;
}

}  // namespace organsim
