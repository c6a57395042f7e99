#pragma once
// A contact sheet like the paper's Figure 4: N frames evenly spaced over a
// run, in a grid of `columns`, each tile labelled with its simulated time.
#include <opencv2/core.hpp>
#include <vector>

namespace organsim {

// Which of `total` frames (0..total-1) go on a sheet of `count` tiles: evenly
// spaced, first and last included, no repeats (fewer when total < count).
std::vector<int> contact_sheet_frames(int total, int count);

// One tile: the frame scaled to tile_width (aspect kept), a 2 px dark border
// and "t = 0.250 s" in its top-left corner. BGR.
cv::Mat make_contact_sheet_tile(const cv::Mat& frame, double t, int tile_width);

// Tiles (all the same size) in rows of `columns`, left to right, top to
// bottom; cells without a tile stay grey. Size = columns x rows tiles, rows =
// ceil(tiles / columns). Throws Error(Usage) for no tiles or columns < 1.
cv::Mat compose_contact_sheet(const std::vector<cv::Mat>& tiles, int columns);

}  // namespace organsim
