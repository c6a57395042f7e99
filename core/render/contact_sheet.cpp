#include "core/render/contact_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "core/util/error.h"

namespace organsim {

std::vector<int> contact_sheet_frames(int total, int count) {
  std::vector<int> frames;
  if (total <= 0 || count <= 0) return frames;
  if (count == 1) return {0};
  for (int i = 0; i < count; ++i) {
    const int f = static_cast<int>(std::lround(static_cast<double>(i) * (total - 1) / (count - 1)));
    if (frames.empty() || frames.back() != f) frames.push_back(f);
  }
  return frames;
}

cv::Mat make_contact_sheet_tile(const cv::Mat& frame, double t, int tile_width) {
  if (frame.empty() || tile_width < 16) throw Error(ErrorKind::Usage, "contact sheet: empty frame or tile narrower than 16 px");
  const int tile_height = std::max(16, static_cast<int>(std::lround(static_cast<double>(frame.rows) * tile_width / frame.cols)));
  cv::Mat tile;
  cv::resize(frame, tile, cv::Size(tile_width, tile_height), 0, 0, cv::INTER_AREA);
  cv::rectangle(tile, {0, 0}, {tile_width - 1, tile_height - 1}, cv::Scalar(60, 60, 60), 2);
  char label[48];
  std::snprintf(label, sizeof label, "t = %.3f s", t);
  const double scale = std::clamp(tile_width / 600.0, 0.35, 0.8);
  int base = 0;
  const cv::Size text = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base);
  // Text on a light box so it reads on any frame content.
  cv::rectangle(tile, {4, 4}, {4 + text.width + 8, 4 + text.height + base + 6}, cv::Scalar(245, 245, 245), cv::FILLED);
  cv::putText(tile, label, {8, 6 + text.height}, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(20, 20, 20), 1, cv::LINE_AA);
  return tile;
}

cv::Mat compose_contact_sheet(const std::vector<cv::Mat>& tiles, int columns) {
  if (tiles.empty()) throw Error(ErrorKind::Usage, "contact sheet: no frames");
  if (columns < 1) throw Error(ErrorKind::Usage, "contact_sheet.columns: expected at least 1");
  const int cols = std::min<int>(columns, static_cast<int>(tiles.size()));
  const int rows = (static_cast<int>(tiles.size()) + cols - 1) / cols;
  const int tw = tiles[0].cols, th = tiles[0].rows;
  cv::Mat sheet(rows * th, cols * tw, CV_8UC3, cv::Scalar(128, 128, 128));
  for (size_t i = 0; i < tiles.size(); ++i) {
    if (tiles[i].cols != tw || tiles[i].rows != th) throw Error(ErrorKind::Usage, "contact sheet: tiles differ in size");
    const int r = static_cast<int>(i) / cols, c = static_cast<int>(i) % cols;
    tiles[i].copyTo(sheet(cv::Rect(c * tw, r * th, tw, th)));
  }
  return sheet;
}

}  // namespace organsim
