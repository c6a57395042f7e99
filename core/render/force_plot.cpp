#include "core/render/force_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/render/image_io.h"
#include "core/render/plot_ticks.h"
#include "core/util/error.h"

namespace organsim {

namespace {

struct Series {
  const char* name;
  cv::Scalar color;  // BGR
  int thickness;
};

}  // namespace

cv::Rect force_plot_area(int width, int height) {
  const int left = 80, right = 150, top = 40, bottom = 60;
  return {left, top, width - left - right, height - top - bottom};
}

cv::Mat draw_force_plot(const std::vector<double>& t, const std::vector<Vec3>& force,
                        const ForcePlotOptions& options) {
  if (t.size() != force.size()) {
    throw Error(ErrorKind::Usage, "force plot: " + std::to_string(t.size()) + " times but " +
                                      std::to_string(force.size()) + " force samples");
  }
  if (options.width < 200 || options.height < 150) {
    throw Error(ErrorKind::Usage, "force plot: size must be at least 200x150 px");
  }
  cv::Mat img(options.height, options.width, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Rect area = force_plot_area(options.width, options.height);
  const cv::Scalar ink(30, 30, 30);
  const auto font = cv::FONT_HERSHEY_SIMPLEX;

  // Data ranges: time from the samples; force covers all curves and 0.
  double t0 = 0, t1 = 1, f0 = -1, f1 = 1;
  if (!t.empty()) {
    t0 = *std::min_element(t.begin(), t.end());
    t1 = *std::max_element(t.begin(), t.end());
    f0 = 0;
    f1 = 0;
    for (const Vec3& f : force) {
      f0 = std::min({f0, f.x(), f.y(), f.z()});
      f1 = std::max({f1, f.x(), f.y(), f.z(), f.norm()});
    }
  }
  if (t1 - t0 <= 0) t1 = t0 + 1;
  if (f1 - f0 <= 0) f1 = f0 + 1;
  const double tstep = nice_step(t1 - t0, 8), fstep = nice_step(f1 - f0, 6);
  t0 = std::floor(t0 / tstep) * tstep;
  t1 = std::ceil(t1 / tstep) * tstep;
  f0 = std::floor(f0 / fstep) * fstep;
  f1 = std::ceil(f1 / fstep) * fstep;

  const auto px = [&](double tv) { return area.x + (tv - t0) / (t1 - t0) * area.width; };
  const auto py = [&](double fv) { return area.y + area.height - (fv - f0) / (f1 - f0) * area.height; };

  draw_grid_and_ticks(img, area, t0, t1, tstep, f0, f1, fstep);
  // Zero force line, darker than the grid.
  if (f0 < 0 && f1 > 0) {
    const int y = static_cast<int>(std::lround(py(0)));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, cv::Scalar(160, 160, 160), 1);
  }
  cv::rectangle(img, area, ink, 1);

  // Curves, clipped to the plot area. |F| is wide and grey underneath, so a
  // component on top of it (often Fz) still shows both.
  const Series series[4] = {{"|F|", cv::Scalar(150, 150, 150), 5},
                            {"Fx", cv::Scalar(40, 40, 220), 2},
                            {"Fy", cv::Scalar(40, 160, 40), 2},
                            {"Fz", cv::Scalar(220, 90, 30), 2}};
  cv::Mat plot = img(area);
  for (int c = 0; c < 4; ++c) {
    std::vector<cv::Point> pts;
    pts.reserve(t.size());
    for (size_t i = 0; i < t.size(); ++i) {
      const double v = c == 0 ? force[i].norm() : force[i][c - 1];
      // Fixed-point coordinates (4 fractional bits) keep dense curves smooth.
      pts.emplace_back(static_cast<int>(std::lround((px(t[i]) - area.x) * 16)),
                       static_cast<int>(std::lround((py(v) - area.y) * 16)));
    }
    if (pts.size() >= 2) {
      cv::polylines(plot, pts, false, series[c].color, series[c].thickness, cv::LINE_AA, 4);
    } else if (pts.size() == 1) {
      cv::circle(plot, pts[0], 3 * 16, series[c].color, cv::FILLED, cv::LINE_AA, 4);
    }
  }

  // Axis labels, title and legend.
  {
    const std::string xl = "time (s)";
    int base = 0;
    const cv::Size size = cv::getTextSize(xl, font, 0.5, 1, &base);
    cv::putText(img, xl, {area.x + area.width / 2 - size.width / 2, options.height - 15}, font, 0.5, ink, 1,
                cv::LINE_AA);
  }
  {
    // Vertical label: draw horizontally, rotate, paste.
    const std::string yl = "force (N)";
    int base = 0;
    const cv::Size size = cv::getTextSize(yl, font, 0.5, 1, &base);
    cv::Mat label(size.height + base + 4, size.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
    cv::putText(label, yl, {2, size.height + 1}, font, 0.5, ink, 1, cv::LINE_AA);
    cv::Mat rotated;
    cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int x = 8, y = area.y + area.height / 2 - rotated.rows / 2;
    if (y >= 0 && y + rotated.rows <= img.rows) rotated.copyTo(img(cv::Rect(x, y, rotated.cols, rotated.rows)));
  }
  cv::putText(img, options.title, {area.x, area.y - 14}, font, 0.6, ink, 1, cv::LINE_AA);
  const int lx = area.x + area.width + 15;
  for (int c = 0; c < 4; ++c) {
    const int y = area.y + 15 + c * 22;
    cv::line(img, {lx, y}, {lx + 28, y}, series[c].color, series[c].thickness, cv::LINE_AA);
    cv::putText(img, std::string(series[c].name) + " (N)", {lx + 34, y + 5}, font, 0.45, ink, 1, cv::LINE_AA);
  }
  return img;
}

void write_force_plot(const std::filesystem::path& path, const std::vector<double>& t,
                      const std::vector<Vec3>& force, const ForcePlotOptions& options) {
  write_image_atomically(path, draw_force_plot(t, force, options));
}

}  // namespace organsim
