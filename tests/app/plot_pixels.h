#pragma once
// Reading the plots organsim writes (study.png, a sweep's results.png) back
// by their pixels: the plot area's frame, and the markers of one colour in
// it, so a test can check that a curve is where its data says, not only
// that the file exists. Built only where the organsim executable draws
// with OpenCV (ORGANSIM_TEST_PLOT_PIXELS, tests/CMakeLists.txt).
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <vector>

namespace organsim::test {

// Whether the BGR pixel p is within `tol` of `colour` on every channel.
inline bool near_colour(const cv::Vec3b& p, const cv::Scalar& colour, int tol) {
  for (int c = 0; c < 3; ++c)
    if (std::abs(p[c] - static_cast<int>(colour[c])) > tol) return false;
  return true;
}

// The plot area's frame: the outermost columns and rows at least half of
// whose pixels are `ink` (within 10). Grid lines have another colour, text
// and curves are short, so only the frame's sides qualify. Empty if none.
inline cv::Rect find_frame(const cv::Mat& img, const cv::Scalar& ink) {
  std::vector<int> in_column(img.cols, 0), in_row(img.rows, 0);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      if (near_colour(img.at<cv::Vec3b>(y, x), ink, 10)) ++in_column[x], ++in_row[y];
  int left = -1, right = -1, top = -1, bottom = -1;
  for (int x = 0; x < img.cols; ++x)
    if (in_column[x] >= img.rows / 2) (left < 0 ? left : right) = x;
  for (int y = 0; y < img.rows; ++y)
    if (in_row[y] >= img.cols / 2) (top < 0 ? top : bottom) = y;
  if (left < 0 || right < 0 || top < 0 || bottom < 0) return {};
  return {left, top, right - left, bottom - top};
}

// Pixels of `colour` (within `tol`) inside `area` (its border excluded),
// opened with a `size` x `size` ellipse so that lines and text thinner than
// it vanish and filled markers stay.
inline cv::Mat colour_mask(const cv::Mat& img, const cv::Scalar& colour, int tol, const cv::Rect& area, int size) {
  cv::Mat mask = cv::Mat::zeros(img.size(), CV_8U);
  for (int y = area.y + 1; y < area.y + area.height; ++y)
    for (int x = area.x + 1; x < area.x + area.width; ++x)
      if (near_colour(img.at<cv::Vec3b>(y, x), colour, tol)) mask.at<uchar>(y, x) = 255;
  cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_ELLIPSE, {size, size}));
  return mask;
}

// Centroids of the mask's connected blobs of at least `min_area` pixels,
// blobs closer than `merge` px joined (a marker cut in two by a line drawn
// over it is one marker).
inline std::vector<cv::Point2d> blobs(const cv::Mat& mask, int min_area, double merge) {
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8);
  struct Blob {
    cv::Point2d sum;
    double area;
  };
  std::vector<Blob> found;
  for (int i = 1; i < n; ++i) {
    const double area = stats.at<int>(i, cv::CC_STAT_AREA);
    const cv::Point2d c(centroids.at<double>(i, 0), centroids.at<double>(i, 1));
    bool joined = false;
    for (Blob& b : found) {
      if (cv::norm(b.sum / b.area - c) < merge) {
        b.sum += c * area, b.area += area, joined = true;
        break;
      }
    }
    if (!joined) found.push_back({c * area, area});
  }
  std::vector<cv::Point2d> out;
  for (const Blob& b : found)
    if (b.area >= min_area) out.push_back(b.sum / b.area);
  return out;
}

// The share of pixels of `colour` (within `tol`) on the ring of radius r
// about c, sampled at 72 angles.
inline double ring_share(const cv::Mat& img, const cv::Point2d& c, double r, const cv::Scalar& colour, int tol) {
  int hits = 0;
  for (int k = 0; k < 72; ++k) {
    const double a = k * 2 * 3.141592653589793 / 72;
    const int x = static_cast<int>(std::lround(c.x + r * std::cos(a))), y = static_cast<int>(std::lround(c.y + r * std::sin(a)));
    if (x >= 0 && y >= 0 && x < img.cols && y < img.rows && near_colour(img.at<cv::Vec3b>(y, x), colour, tol)) ++hits;
  }
  return hits / 72.0;
}

// A curve's row in each column of `area` (its border included), the mean
// row of the pixels of `colour` (within `tol`) there; NaN where it has none.
// A line's row at that column, a marker on it (symmetric) not moving it.
inline std::vector<double> curve_rows(const cv::Mat& img, const cv::Scalar& colour, int tol, const cv::Rect& area) {
  std::vector<double> rows;
  for (int x = area.x; x <= area.x + area.width; ++x) {
    double sum = 0;
    int n = 0;
    for (int y = area.y; y <= area.y + area.height; ++y)
      if (near_colour(img.at<cv::Vec3b>(y, x), colour, tol)) sum += y, ++n;
    rows.push_back(n ? sum / n : std::nan(""));
  }
  return rows;
}

// Least squares v = a + b u over the pairs; the largest residual, |v - a - b u|.
struct LineFit {
  double a = 0, b = 0, worst = 0;
};
inline LineFit fit_line(const std::vector<double>& u, const std::vector<double>& v) {
  const double n = static_cast<double>(u.size());
  double su = 0, sv = 0, suu = 0, suv = 0;
  for (size_t i = 0; i < u.size(); ++i) su += u[i], sv += v[i], suu += u[i] * u[i], suv += u[i] * v[i];
  LineFit f;
  f.b = (n * suv - su * sv) / (n * suu - su * su);
  f.a = (sv - f.b * su) / n;
  for (size_t i = 0; i < u.size(); ++i) f.worst = std::max(f.worst, std::abs(v[i] - f.a - f.b * u[i]));
  return f;
}

}  // namespace organsim::test
