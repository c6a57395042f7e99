#pragma once
// Per-point scalars for the colour map (spring strain, displacement), the
// colour scale itself and its legend. Scalars are computed on the CPU from
// positions in the Model's internal numbering.
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/model/model.h"
#include "core/render/frame_options.h"

namespace organsim {

// Mean |l/l0 - 1| over the springs of each point (dimensionless).
void point_strain(const Model& model, const std::vector<Vec3>& x, std::vector<float>& out);
// |x - rest| per point, m.
void point_displacement(const Model& model, const std::vector<Vec3>& x, std::vector<float>& out);
// |x - reference| per point, m (the frames measure from the run's start).
void point_displacement(const std::vector<Vec3>& reference, const std::vector<Vec3>& x, std::vector<float>& out);

// The colour scale: s in [0, 1] (clamped) -> RGB in [0, 1]. Dark blue through
// cyan, green and yellow to red, monotonic in lightness up to yellow so that
// low and high values stay apart in greyscale prints too.
Vec3f colormap_rgb(float s);

// Largest value (0 when all are 0), or `fixed_max` when it is > 0.
double colormap_range_max(const std::vector<float>& values, double fixed_max);

// Draws a vertical colour bar at the right edge of a BGR image, labelled with
// `title` and the min/max values (e.g. "strain", 0, 0.12, "" or "displacement",
// 0, 0.004, "m").
void draw_colormap_legend(cv::Mat& bgr, const std::string& title, double min_value,
                          double max_value, const std::string& unit);

// Name and unit used by the legend for a colour map.
std::string colormap_title(Colormap map);
std::string colormap_unit(Colormap map);

}  // namespace organsim
