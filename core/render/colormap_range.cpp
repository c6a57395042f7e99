#include "core/render/colormap_range.h"

#include <algorithm>
#include <limits>

#include "core/render/colormap.h"

namespace organsim {

namespace {
constexpr int kPathSamples = 200;  // along the run; 5 ms apart for a 1 s run
}

double tool_reach(const ToolSpec& tool, const std::vector<Vec3>& start, double duration) {
  double reach = 0;
  const Vec3 grasped_at = tool.position_at(tool.grasp_time);
  for (int k = 0; k <= kPathSamples; ++k) {
    const double t = duration * k / kPathSamples;
    const Vec3 c = tool.position_at(t);
    if (tool.mode == ToolMode::Pull) {
      const bool held = t >= tool.grasp_time && (!tool.release_time || t <= *tool.release_time);
      if (held) reach = std::max(reach, (c - grasped_at).norm());
      continue;
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (const Vec3& p : start) nearest = std::min(nearest, (p - c).norm());
    reach = std::max(reach, tool.radius - nearest);
  }
  return reach;
}

ColormapRange colormap_range(const StyleOptions& style, const std::optional<ToolSpec>& tool,
                             const std::vector<Vec3>& start, double duration) {
  if (style.colormap_max > 0) return {style.colormap_max, "scenario"};
  if (!tool) return {0, "first frame"};
  const double reach = tool_reach(*tool, start, duration);
  if (!(reach > 0)) return {0, "first frame"};
  return {style.colormap == Colormap::Strain ? reach / tool->radius : reach, "estimate"};
}

std::string colormap_legend_title(Colormap map, const ColormapRange& range) {
  return colormap_title(map) + " (fixed, " + range.source + ")";
}

}  // namespace organsim
