#pragma once
// Axis ticks and grid shared by the plots drawn with OpenCV (force_plot, xy_plot).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <string>

namespace organsim {

// Tick step of 1, 2 or 5 x 10^k giving about `target` intervals over span.
inline double nice_step(double span, int target) {
  const double raw = span / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  const double m = r < 1.5 ? 1 : r < 3.5 ? 2 : r < 7.5 ? 5 : 10;
  return m * mag;
}

// Enough decimals to tell neighbouring ticks apart.
inline std::string tick_label(double v, double step) {
  const int decimals = std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 9);
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

// Grid lines, tick marks and tick labels of both axes around `area`, for x
// ticks every xstep over [x0, x1] and y ticks every ystep over [y0, y1]
// (ranges already rounded out to whole steps).
inline void draw_grid_and_ticks(cv::Mat& img, const cv::Rect& area, double x0, double x1, double xstep, double y0,
                                double y1, double ystep) {
  const cv::Scalar ink(30, 30, 30), grid(225, 225, 225);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;
  const int bottom = area.y + area.height;
  for (double v = x0; v <= x1 + xstep * 1e-6; v += xstep) {
    const int x = static_cast<int>(std::lround(area.x + (v - x0) / (x1 - x0) * area.width));
    cv::line(img, {x, area.y}, {x, bottom}, grid, 1);
    cv::line(img, {x, bottom}, {x, bottom + 5}, ink, 1);
    const std::string s = tick_label(v, xstep);
    int base = 0;
    const cv::Size size = cv::getTextSize(s, font, 0.4, 1, &base);
    cv::putText(img, s, {x - size.width / 2, bottom + 20}, font, 0.4, ink, 1, cv::LINE_AA);
  }
  for (double v = y0; v <= y1 + ystep * 1e-6; v += ystep) {
    const int y = static_cast<int>(std::lround(bottom - (v - y0) / (y1 - y0) * area.height));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, grid, 1);
    cv::line(img, {area.x - 5, y}, {area.x, y}, ink, 1);
    const std::string s = tick_label(v, ystep);
    int base = 0;
    const cv::Size size = cv::getTextSize(s, font, 0.4, 1, &base);
    cv::putText(img, s, {area.x - 8 - size.width, y + 4}, font, 0.4, ink, 1, cv::LINE_AA);
  }
}

}  // namespace organsim
