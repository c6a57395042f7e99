#include "core/render/label_colors.h"

#include <algorithm>
#include <array>
#include <string>
#include <opencv2/imgproc.hpp>

namespace organsim {

Vec3f label_rgb(int32_t label) {
  // Okabe & Ito (2008), without black: every pair stays apart for the common
  // colour-vision deficiencies, and none is the tissue red of plain frames.
  static const std::array<Vec3f, 7> kPalette = {
      Vec3f(0.902f, 0.624f, 0.000f), Vec3f(0.337f, 0.706f, 0.914f), Vec3f(0.000f, 0.620f, 0.451f),
      Vec3f(0.941f, 0.894f, 0.259f), Vec3f(0.000f, 0.447f, 0.698f), Vec3f(0.835f, 0.369f, 0.000f),
      Vec3f(0.800f, 0.475f, 0.655f)};
  if (label == 0) return Vec3f(0.75f, 0.75f, 0.75f);
  const int64_t k = (static_cast<int64_t>(label) - 1) % 7;
  return kPalette[static_cast<size_t>(k < 0 ? k + 7 : k)];
}

std::vector<int32_t> face_labels(const Model& model, const std::vector<int32_t>& face_tet) {
  std::vector<int32_t> labels(face_tet.size(), 0);
  if (model.tet_label.empty()) return labels;
  for (size_t f = 0; f < face_tet.size(); ++f) labels[f] = model.tet_label[face_tet[f]];
  return labels;
}

void draw_label_key(cv::Mat& bgr, const std::vector<int32_t>& labels) {
  // Sizes relative to the image, as the colour scale's legend.
  const double font = std::clamp(bgr.rows / 900.0, 0.3, 0.7);
  const auto face = cv::FONT_HERSHEY_SIMPLEX;
  int base = 0;
  int text_w = cv::getTextSize("label", face, font, 1, &base).width;
  for (int32_t l : labels) text_w = std::max(text_w, cv::getTextSize(std::to_string(l), face, font, 1, &base).width);
  const int line_h = cv::getTextSize("0", face, font, 1, &base).height * 2;
  const int swatch = std::max(8, line_h - 4);
  const int margin = std::max(6, bgr.cols / 60);
  const int x0 = bgr.cols - margin - text_w - swatch - 4;
  int y = std::max(line_h, (bgr.rows - line_h * static_cast<int>(labels.size() + 1)) / 2);
  const cv::Scalar ink(20, 20, 20);
  cv::putText(bgr, "label", {x0, y}, face, font, ink, 1, cv::LINE_AA);
  for (int32_t l : labels) {
    y += line_h;
    const Vec3f c = label_rgb(l) * 255.0f;
    cv::rectangle(bgr, {x0, y - swatch + 2}, {x0 + swatch - 1, y + 1}, cv::Scalar(c.z(), c.y(), c.x()), cv::FILLED);
    cv::rectangle(bgr, {x0, y - swatch + 2}, {x0 + swatch - 1, y + 1}, ink, 1);
    cv::putText(bgr, std::to_string(l), {x0 + swatch + 4, y}, face, font, ink, 1, cv::LINE_AA);
  }
}

}  // namespace organsim
