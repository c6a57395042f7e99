#pragma once
// The colour map's range for a run, fixed before the first frame so that a
// colour means the same value in every frame and on the contact sheet: from
// the scenario (style.colormap_max) or estimated from what the tool will do.
#include <optional>
#include <string>
#include <vector>

#include "core/render/frame_options.h"
#include "core/scenario/tool_spec.h"

namespace organsim {

struct ColormapRange {
  double max = 0;      // top of the scale (m or dimensionless); 0: not known yet
  std::string source;  // "scenario", "estimate" or "first frame", for the legend
};

// How far the tool will move the model: for a push, the deepest its sphere
// reaches into `start` (positions at t = 0) along its path over [0, duration];
// for a pull, the farthest it travels from where it grasps. m.
double tool_reach(const ToolSpec& tool, const std::vector<Vec3>& start, double duration);

// style.colormap_max when set; else from tool_reach: displacement = reach,
// strain = reach / tool radius (the order of the strain of a dent of that
// depth under a sphere of that radius). max = 0 when there is no tool or it
// never touches the model: the first frame with any value then sets it.
ColormapRange colormap_range(const StyleOptions& style, const std::optional<ToolSpec>& tool,
                             const std::vector<Vec3>& start, double duration);

// The legend's title: "displacement (fixed, estimate)".
std::string colormap_legend_title(Colormap map, const ColormapRange& range);

}  // namespace organsim
