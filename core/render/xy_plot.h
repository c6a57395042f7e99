#pragma once
// A plain line plot of named (x, y) series with axes, ticks and a legend,
// drawn with OpenCV: the validation tables' error against cell size and the
// fit's measured against simulated force.
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace organsim {

struct XySeries {
  std::string name;
  std::vector<double> x, y;  // same length
  bool markers = true;       // circles at the samples
  bool line = true;          // joined in order
};

struct XyPlotOptions {
  int width = 900, height = 550;  // px
  std::string title, x_label, y_label;
  // Horizontal band drawn behind the data (e.g. theory +-10 %), in y units.
  std::optional<std::pair<double, double>> band;
};

// The plot area (inside the axes) for an image of the given size.
cv::Rect xy_plot_area(int width, int height);

// BGR image. Throws Error(Usage) when a series' x and y lengths differ or the
// size is below 300x200.
cv::Mat draw_xy_plot(const std::vector<XySeries>& series, const XyPlotOptions& options);

// draw_xy_plot written atomically as PNG (Error(Output) on failure).
void write_xy_plot(const std::filesystem::path& path, const std::vector<XySeries>& series,
                   const XyPlotOptions& options);

}  // namespace organsim
