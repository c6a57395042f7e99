#include "core/render/colormap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace organsim {

void point_strain(const Model& model, const std::vector<Vec3>& x, std::vector<float>& out) {
  const int32_t n = model.npoint();
  std::vector<double> sum(n, 0.0);
  std::vector<int32_t> count(n, 0);
  for (int32_t s = 0; s < model.first_suture(); ++s) {  // the tissue's strain, not the sutures'
    const auto [a, b] = model.spring_ends[s];
    const double strain = std::abs((x[a] - x[b]).norm() / model.spring_rest[s] - 1.0);
    sum[a] += strain;
    sum[b] += strain;
    ++count[a];
    ++count[b];
  }
  out.resize(n);
  for (int32_t i = 0; i < n; ++i) out[i] = count[i] ? static_cast<float>(sum[i] / count[i]) : 0.0f;
}

void point_displacement(const Model& model, const std::vector<Vec3>& x, std::vector<float>& out) {
  point_displacement(model.rest_position, x, out);
}

void point_displacement(const std::vector<Vec3>& reference, const std::vector<Vec3>& x, std::vector<float>& out) {
  out.resize(reference.size());
  for (size_t i = 0; i < reference.size(); ++i) out[i] = static_cast<float>((x[i] - reference[i]).norm());
}

Vec3f colormap_rgb(float s) {
  // Piecewise linear through evenly spaced stops.
  static const std::array<Vec3f, 5> stops = {Vec3f(0.15f, 0.10f, 0.55f), Vec3f(0.10f, 0.55f, 0.85f),
                                             Vec3f(0.25f, 0.75f, 0.35f), Vec3f(0.95f, 0.85f, 0.15f),
                                             Vec3f(0.85f, 0.15f, 0.10f)};
  if (!(s > 0)) s = 0;  // also maps NaN to the bottom of the scale
  if (s > 1) s = 1;
  const float pos = s * static_cast<float>(stops.size() - 1);
  const int i = std::min(static_cast<int>(pos), static_cast<int>(stops.size()) - 2);
  const float f = pos - static_cast<float>(i);
  return stops[i] * (1 - f) + stops[i + 1] * f;
}

double colormap_range_max(const std::vector<float>& values, double fixed_max) {
  if (fixed_max > 0) return fixed_max;
  double m = 0;
  for (float v : values) m = std::max(m, static_cast<double>(v));
  return m;
}

namespace {
std::string format_value(double v, const std::string& unit) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g%s%s", v, unit.empty() ? "" : " ", unit.c_str());
  return buf;
}
}  // namespace

void draw_colormap_legend(cv::Mat& bgr, const std::string& title, double min_value,
                          double max_value, const std::string& unit) {
  // Sizes relative to the image so small frames stay readable.
  const double font = std::clamp(bgr.rows / 900.0, 0.3, 0.7);
  const auto face = cv::FONT_HERSHEY_SIMPLEX;
  const std::string top = format_value(max_value, unit), bottom = format_value(min_value, unit);
  int base = 0;
  const cv::Size top_size = cv::getTextSize(top, face, font, 1, &base);
  const cv::Size bottom_size = cv::getTextSize(bottom, face, font, 1, &base);
  int title_base = 0;  // how far the title's descenders reach below its baseline
  const cv::Size title_size = cv::getTextSize(title, face, font, 1, &title_base);
  const int bar_w = std::max(8, bgr.cols / 40);
  const int bar_h = std::max(40, bgr.rows / 2);
  const int margin = std::max(6, bgr.cols / 60);
  const int label_w = std::max(top_size.width, bottom_size.width) + 4;
  const int x0 = bgr.cols - margin - label_w - bar_w;
  const int y0 = (bgr.rows - bar_h) / 2;
  // The title's place (above the bar, kept inside the image on the right):
  // its lowest ink (the descenders of "(", "p", ",": title_base below the
  // baseline) a text height clear of the bar's frame (row y0 - 1), so the
  // two stay apart when the contact sheet halves the frame
  // (ColorMap.LegendTitleClearsTheBar).
  const int title_x = std::max(0, std::min(x0, bgr.cols - margin - title_size.width));
  const int title_baseline = std::max(title_size.height, y0 - 1 - title_size.height - title_base);
  // A light backing under each text, so it stays readable where the model
  // lies behind it.
  const auto back = [&](cv::Point baseline_left, const cv::Size& size, int below) {
    const cv::Rect r = cv::Rect(baseline_left.x - 2, baseline_left.y - size.height - 2, size.width + 4,
                                size.height + below + 4) & cv::Rect(0, 0, bgr.cols, bgr.rows);
    cv::Mat area = bgr(r);
    cv::addWeighted(area, 0.3, cv::Mat(area.size(), area.type(), cv::Scalar(250, 250, 250)), 0.7, 0.0, area);
  };
  const int tx = x0 + bar_w + 4;
  back({title_x, title_baseline}, title_size, title_base);
  back({tx, y0 + top_size.height}, top_size, base);
  back({tx, y0 + bar_h}, bottom_size, base);
  for (int y = 0; y < bar_h; ++y) {
    const float s = 1.0f - static_cast<float>(y) / static_cast<float>(bar_h - 1);  // max at the top
    const Vec3f c = colormap_rgb(s) * 255.0f;
    cv::line(bgr, {x0, y0 + y}, {x0 + bar_w - 1, y0 + y}, cv::Scalar(c.z(), c.y(), c.x()));
  }
  const cv::Scalar ink(20, 20, 20);
  cv::rectangle(bgr, {x0 - 1, y0 - 1}, {x0 + bar_w, y0 + bar_h}, ink, 1);
  cv::putText(bgr, top, {tx, y0 + top_size.height}, face, font, ink, 1, cv::LINE_AA);
  cv::putText(bgr, bottom, {tx, y0 + bar_h}, face, font, ink, 1, cv::LINE_AA);
  cv::putText(bgr, title, {title_x, title_baseline}, face, font, ink, 1, cv::LINE_AA);
}

std::string colormap_title(Colormap map) {
  switch (map) {
    case Colormap::Strain: return "strain";
    case Colormap::Displacement: return "displacement";
    case Colormap::Label: return "label";
    case Colormap::None: break;
  }
  return "";
}

std::string colormap_unit(Colormap map) { return map == Colormap::Displacement ? "m" : ""; }

}  // namespace organsim
