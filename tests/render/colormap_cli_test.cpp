// Colour map scalars and legend, `organsim render` end to end, and the
// frame cost measurement bench uses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sys/wait.h>

#include "core/mesh/mesh_io.h"
#include "core/model/model.h"
#include "core/render/colormap.h"
#include "core/render/frame_cost.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace colormap_cli_test {
namespace {

namespace fs = std::filesystem;

TEST(ColorMap, StrainOfAStretchedModelIsTheStretch) {
  const TetMesh mesh = make_box_tet_mesh(Vec3(0, 0, 0), Vec3(1, 1, 1), 2, 2, 2);
  const Model model = build_model(mesh, Material{}, ModelOptions{}, "cube");
  // Uniform scaling by 1.1 stretches every spring by 10 %: strain 0.1 at
  // every point (float output: 1e-6).
  std::vector<Vec3> x = model.rest_position;
  for (Vec3& p : x) p *= 1.1;
  std::vector<float> strain, displacement;
  point_strain(model, x, strain);
  ASSERT_EQ(strain.size(), static_cast<size_t>(model.npoint()));
  for (float s : strain) EXPECT_NEAR(s, 0.1, 1e-6);
  // Displacement |0.1 x|: largest at the far corner (1,1,1): 0.1 * sqrt(3).
  point_displacement(model, x, displacement);
  EXPECT_NEAR(colormap_range_max(displacement, 0), 0.1 * std::sqrt(3.0), 1e-6);
  EXPECT_EQ(colormap_range_max(displacement, 0.5), 0.5);  // a fixed range wins
}

TEST(ColorMap, ScaleRunsFromDarkBlueToRedAndLegendShowsIt) {
  const Vec3f lo = colormap_rgb(0), hi = colormap_rgb(1);
  EXPECT_GT(lo.z(), lo.x());  // blue end
  EXPECT_GT(hi.x(), hi.z());  // red end
  EXPECT_EQ(colormap_rgb(-1), lo);  // clamped
  EXPECT_EQ(colormap_rgb(2), hi);
  cv::Mat img(300, 400, CV_8UC3, cv::Scalar(255, 255, 255));
  draw_colormap_legend(img, "strain", 0.0, 0.12, "");
  // The bar has the high colour at the top and the low colour at the bottom
  // (an upside-down legend swaps them): the mean row of each colour's pixels,
  // matched within 3 of 255 per channel (the bar rounds, the test truncates).
  const auto mean_row_of = [&](const Vec3f& rgb) {
    const cv::Scalar bgr(rgb.z() * 255, rgb.y() * 255, rgb.x() * 255);
    cv::Mat mask;
    cv::inRange(img, bgr - cv::Scalar::all(3), bgr + cv::Scalar::all(3), mask);
    std::vector<cv::Point> at;
    cv::findNonZero(mask, at);
    double sum = 0;
    for (const cv::Point& p : at) sum += p.y;
    EXPECT_GT(at.size(), 5u) << "colour not found in the legend";
    return at.empty() ? 0.0 : sum / static_cast<double>(at.size());
  };
  const double top = mean_row_of(hi), bottom = mean_row_of(lo);
  // The bar is half the image tall (150 rows): its ends are ~150 rows apart.
  EXPECT_LT(top + 100, bottom) << "high colour at row " << top << ", low colour at row " << bottom;
  // Text was written (dark pixels right of the bar).
  cv::Mat grey;
  cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(grey(cv::Rect(300, 0, 100, 300)) < 100), 20);
}

// The legend's title stays clear of the colour bar, in a 640 x 480 frame and
// in its half-size tile on a contact sheet (cv::INTER_AREA, as
// contact_sheet.cpp): between the title's lowest ink left of the bar and the
// bar's frame lie at least 4 rows of background (the title "runs into" the
// bar when its descenders sit a few rows above it).
TEST(ColorMap, LegendTitleClearsTheBar) {
  cv::Mat frame(480, 640, CV_8UC3, cv::Scalar(255, 255, 255));
  draw_colormap_legend(frame, "displacement (fixed, scenario)", 0.0, 0.015, "m");
  cv::Mat tile;
  cv::resize(frame, tile, cv::Size(320, 240), 0, 0, cv::INTER_AREA);
  for (const cv::Mat* img : {&frame, &tile}) {
    SCOPED_TRACE(img == &frame ? "640 x 480 frame" : "320 x 240 tile");
    // The bar: its rows and columns of saturated colour.
    int bar_top = img->rows, bar_left = img->cols, bar_right = -1;
    for (int y = 0; y < img->rows; ++y)
      for (int x = 0; x < img->cols; ++x) {
        const cv::Vec3b p = img->at<cv::Vec3b>(y, x);
        const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
        if (hi - lo > 120) {
          bar_top = std::min(bar_top, y);
          bar_left = std::min(bar_left, x);
          bar_right = std::max(bar_right, x);
        }
      }
    ASSERT_LT(bar_right, img->cols) << "no colour bar";
    ASSERT_GT(bar_right - bar_left, 3);
    // The title: ink (any darkening of the background) left of the bar and
    // above its middle; its lowest row.
    int title_bottom = -1, title_top = img->rows;
    for (int y = 0; y < bar_top + img->rows / 8; ++y)
      for (int x = 0; x < bar_left - 2; ++x) {
        const cv::Vec3b p = img->at<cv::Vec3b>(y, x);
        if (std::min({p[0], p[1], p[2]}) < 230) {
          title_bottom = std::max(title_bottom, y);
          title_top = std::min(title_top, y);
        }
      }
    ASSERT_GE(title_bottom, 0) << "no title left of the bar";
    EXPECT_GE(title_top, 0);
    // The bar's frame is drawn one row above its colour.
    const int gap = (bar_top - 1) - title_bottom - 1;
    EXPECT_GE(gap, 4) << "title rows " << title_top << ".." << title_bottom << ", bar from row " << bar_top;
  }
}

TEST(RenderCommand, WritesAStillOfATetMeshAndRejectsBadCameras) {
  const fs::path dir = fs::path(ORGANSIM_TEST_TMP) / "render_cmd";
  fs::remove_all(dir);
  fs::create_directories(dir);
  write_tet_mesh(dir / "box.vtk", make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.08, 0.06), 4, 4, 3));
  const fs::path image = dir / "box.png";
  const std::string cmd = std::string(ORGANSIM_EXE) + " render " + (dir / "box.vtk").string() + " -o " +
                          image.string() + " --width 240 --height 180 --background 0,0,0 --wireframe > " +
                          (dir / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const cv::Mat img = cv::imread(image.string());
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 240);
  EXPECT_EQ(img.rows, 180);
  const cv::Mat object = testing::differs_from(img, cv::Vec3b(0, 0, 0), 8);
  // Auto-fit: the box is in the middle, the corners are background.
  EXPECT_GT(cv::countNonZero(object(cv::Rect(110, 80, 20, 20))), 350);
  EXPECT_EQ(cv::countNonZero(object(cv::Rect(0, 0, 15, 15))), 0);
  // A camera vector with two numbers is a usage error (exit 2), no file.
  const fs::path bad = dir / "bad.png";
  const std::string bad_cmd = std::string(ORGANSIM_EXE) + " render " + (dir / "box.vtk").string() + " -o " +
                              bad.string() + " --camera-position 1,2 > /dev/null 2>&1";
  const int status = std::system(bad_cmd.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  EXPECT_FALSE(fs::exists(bad));
}

TEST(FrameCost, MeasuresEveryStage) {
  const Model model =
      build_model(make_box_tet_mesh(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), 4, 4, 4), Material{}, ModelOptions{}, "box");
  const FrameCost cost = measure_frame_cost(model, 160, 120, 3);
  EXPECT_EQ(cost.frames, 3);
  EXPECT_EQ(cost.triangles, static_cast<size_t>(4 * 3 * 16));
  // Times are positive (their size is bench's business, not a test's).
  EXPECT_GT(cost.render_ms, 0.0);
  EXPECT_GT(cost.readback_ms, 0.0);
  EXPECT_GT(cost.png_ms, 0.0);
  EXPECT_GT(cost.video_ms, 0.0);
  EXPECT_FALSE(cost.renderer.empty());
}

}  // namespace
}  // namespace colormap_cli_test
}  // namespace organsim
