#pragma once
// OUTDIR/forces.png: the tool's reaction force against time, drawn with
// OpenCV (magnitude and x/y/z components, axes in s and N, ticks, legend).
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

struct ForcePlotOptions {
  int width = 900;    // px
  int height = 500;   // px
  std::string title = "tool reaction force";
};

// The plot area (inside the axes) for an image of the given size, so callers
// and tests agree on where the curves are.
cv::Rect force_plot_area(int width, int height);

// t in s, force in N, same length (may be empty: axes only). BGR image.
// Throws Error(Usage) when the lengths differ or the size is below 200x150.
cv::Mat draw_force_plot(const std::vector<double>& t, const std::vector<Vec3>& force,
                        const ForcePlotOptions& options = {});

// draw_force_plot, written atomically as PNG (Error(Output) on failure).
void write_force_plot(const std::filesystem::path& path, const std::vector<double>& t,
                      const std::vector<Vec3>& force, const ForcePlotOptions& options = {});

}  // namespace organsim
