// The validation and fit plots (core/render/xy_plot.h): pixels where the
// data are, the band where asked, errors for bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/render/xy_plot.h"
#include "core/util/error.h"

namespace organsim {
namespace xy_plot_test {
namespace {

TEST(XyPlot, ALineFromLowerLeftToUpperRightAndTheBand) {
  XySeries s{"ramp", {0, 1, 2, 3, 4}, {0, 1, 2, 3, 4}, true, true};
  XyPlotOptions o;
  o.band = std::make_pair(1.0, 2.0);
  const cv::Mat img = draw_xy_plot({s}, o);
  ASSERT_EQ(img.cols, o.width);
  ASSERT_EQ(img.rows, o.height);
  const cv::Rect area = xy_plot_area(o.width, o.height);
  // The first series' colour (BGR 200, 80, 30) near the data's corners:
  // (0, 0) at the lower left and (4, 4) at the upper right of the area.
  auto coloured_near = [&](int x, int y) {
    int n = 0;
    for (int dy = -6; dy <= 6; ++dy)
      for (int dx = -6; dx <= 6; ++dx) {
        const cv::Vec3b p = img.at<cv::Vec3b>(std::clamp(y + dy, 0, img.rows - 1), std::clamp(x + dx, 0, img.cols - 1));
        n += std::abs(p[0] - 200) < 40 && std::abs(p[1] - 80) < 40 && std::abs(p[2] - 30) < 40;
      }
    return n;
  };
  EXPECT_GT(coloured_near(area.x, area.y + area.height), 5);
  EXPECT_GT(coloured_near(area.x + area.width, area.y), 5);
  EXPECT_EQ(coloured_near(area.x + area.width, area.y + area.height), 0);  // lower right: no data
  // The band (light green) fills the area between y = 1 and 2, left of the line.
  const cv::Vec3b band = img.at<cv::Vec3b>(area.y + area.height * 11 / 20, area.x + area.width / 20);
  EXPECT_EQ(band, cv::Vec3b(215, 240, 215));
  // Grid and ticks every 0.5 (nice_step over 0..4): light grey grid lines
  // through x = 2 and y = 3 away from the data, a dark tick mark below x = 2.
  const int x2 = static_cast<int>(std::lround(area.x + 0.5 * area.width));
  const int y3 = static_cast<int>(std::lround(area.y + 0.25 * area.height));
  const int bottom = area.y + area.height;
  EXPECT_EQ(img.at<cv::Vec3b>(area.y + 3, x2), cv::Vec3b(225, 225, 225));
  EXPECT_EQ(img.at<cv::Vec3b>(y3, area.x + 3), cv::Vec3b(225, 225, 225));
  EXPECT_EQ(img.at<cv::Vec3b>(bottom + 3, x2), cv::Vec3b(30, 30, 30));
}

TEST(XyPlot, MismatchedSeriesIsAUsageError) {
  XySeries s{"bad", {0, 1}, {0}, true, true};
  try {
    draw_xy_plot({s}, {});
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Usage);
    EXPECT_NE(std::string(e.what()).find("'bad'"), std::string::npos);
  }
}

}  // namespace
}  // namespace xy_plot_test
}  // namespace organsim
