#include "core/render/xy_plot.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/render/image_io.h"
#include "core/render/plot_ticks.h"
#include "core/util/error.h"

namespace organsim {

cv::Rect xy_plot_area(int width, int height) {
  const int left = 90, right = 260, top = 45, bottom = 60;
  return {left, top, width - left - right, height - top - bottom};
}

cv::Mat draw_xy_plot(const std::vector<XySeries>& series, const XyPlotOptions& options) {
  if (options.width < 300 || options.height < 200) throw Error(ErrorKind::Usage, "xy plot: size must be at least 300x200 px");
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const XySeries& s : series) {
    if (s.x.size() != s.y.size())
      throw Error(ErrorKind::Usage, "xy plot: series '" + s.name + "' has " + std::to_string(s.x.size()) +
                                        " x values but " + std::to_string(s.y.size()) + " y values");
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
    }
  }
  if (options.band) y0 = std::min(y0, options.band->first), y1 = std::max(y1, options.band->second);
  if (x0 > x1) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (x1 - x0 <= 0) x0 -= 0.5 * std::max(std::abs(x0), 1e-12), x1 += 0.5 * std::max(std::abs(x1), 1e-12);
  if (y1 - y0 <= 0) y0 -= 0.5 * std::max(std::abs(y0), 1e-12), y1 += 0.5 * std::max(std::abs(y1), 1e-12);
  const double xstep = nice_step(x1 - x0, 8), ystep = nice_step(y1 - y0, 6);
  x0 = std::floor(x0 / xstep) * xstep, x1 = std::ceil(x1 / xstep) * xstep;
  y0 = std::floor(y0 / ystep) * ystep, y1 = std::ceil(y1 / ystep) * ystep;

  cv::Mat img(options.height, options.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Rect area = xy_plot_area(options.width, options.height);
  const cv::Scalar ink(30, 30, 30);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const auto px = [&](double v) { return area.x + (v - x0) / (x1 - x0) * area.width; };
  const auto py = [&](double v) { return area.y + area.height - (v - y0) / (y1 - y0) * area.height; };
  const auto at = [&](double x, double y) {
    return cv::Point(static_cast<int>(std::lround(px(x))), static_cast<int>(std::lround(py(y))));
  };

  if (options.band) {
    cv::rectangle(img, at(x0, options.band->second), at(x1, options.band->first), cv::Scalar(215, 240, 215),
                  cv::FILLED);
  }
  draw_grid_and_ticks(img, area, x0, x1, xstep, y0, y1, ystep);
  cv::rectangle(img, area, ink, 1);

  static const cv::Scalar colours[] = {{200, 80, 30}, {30, 140, 230}, {60, 170, 60}, {160, 60, 200},
                                       {40, 40, 200}, {120, 120, 0},  {0, 120, 160}, {90, 90, 90}};
  cv::Mat plot = img(area);
  for (size_t k = 0; k < series.size(); ++k) {
    const XySeries& s = series[k];
    const cv::Scalar c = colours[k % 8];
    std::vector<cv::Point> pts;
    for (size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) pts.push_back(at(s.x[i], s.y[i]) - area.tl());
    if (s.line && pts.size() >= 2) cv::polylines(plot, pts, false, c, 2, cv::LINE_AA);
    if (s.markers)
      for (const cv::Point& p : pts) cv::circle(plot, p, 4, c, cv::FILLED, cv::LINE_AA);
    const int y = area.y + 15 + static_cast<int>(k) * 22, lx = area.x + area.width + 15;
    cv::line(img, {lx, y}, {lx + 28, y}, c, 2, cv::LINE_AA);
    cv::putText(img, s.name, {lx + 34, y + 5}, font, 0.42, ink, 1, cv::LINE_AA);
  }
  int base = 0;
  const cv::Size xs = cv::getTextSize(options.x_label, font, 0.5, 1, &base);
  cv::putText(img, options.x_label, {area.x + area.width / 2 - xs.width / 2, options.height - 15}, font, 0.5, ink, 1,
              cv::LINE_AA);
  cv::putText(img, options.y_label, {8, area.y - 12}, font, 0.5, ink, 1, cv::LINE_AA);
  cv::putText(img, options.title, {area.x + 160, area.y - 14}, font, 0.55, ink, 1, cv::LINE_AA);
  return img;
}

void write_xy_plot(const std::filesystem::path& path, const std::vector<XySeries>& series,
                   const XyPlotOptions& options) {
  write_image_atomically(path, draw_xy_plot(series, options));
}

}  // namespace organsim
