// forces.png and the contact sheet composition: OpenCV only, no GL.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/render/contact_sheet.h"
#include "core/render/force_plot.h"
#include "core/render/force_plot_recorder.h"
#include "tests/render/render_test_util.h"
#include "core/util/error.h"

namespace organsim {
namespace plots_test {
namespace {

namespace fs = std::filesystem;

// Pixels of exactly-ish one BGR colour (anti-aliasing blends the rest).
int count_colour(const cv::Mat& m, const cv::Vec3b& c, int tol) {
  cv::Mat near;
  cv::inRange(m, cv::Scalar(std::max(c[0] - tol, 0), std::max(c[1] - tol, 0), std::max(c[2] - tol, 0)),
              cv::Scalar(std::min(c[0] + tol, 255), std::min(c[1] + tol, 255), std::min(c[2] + tol, 255)), near);
  return cv::countNonZero(near);
}

TEST(ForcePlot, CurvesLieInsideThePlotAreaAtTheRequestedSize) {
  std::vector<double> t;
  std::vector<Vec3> f;
  for (int i = 0; i <= 1000; ++i) {
    t.push_back(i * 1e-3);
    f.emplace_back(0.3 * std::sin(10 * t.back()), -0.2, 1.5 * t.back());
  }
  const fs::path path = fs::path(ORGANSIM_TEST_TMP) / "plots" / "forces.png";
  fs::remove(path);
  ForcePlotOptions options;
  options.width = 700;
  options.height = 420;
  write_force_plot(path, t, f, options);
  const cv::Mat img = cv::imread(path.string());
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 700);
  EXPECT_EQ(img.rows, 420);
  const cv::Rect area = force_plot_area(700, 420);
  const cv::Mat inside = img(cv::Rect(area.x + 2, area.y + 2, area.width - 4, area.height - 4));
  // Each series' colour (BGR as drawn) appears along the curve: at least
  // half the plot width in pixels (each curve spans the full time axis).
  EXPECT_GT(count_colour(inside, {40, 40, 220}, 20), area.width / 2);   // Fx
  EXPECT_GT(count_colour(inside, {40, 160, 40}, 20), area.width / 2);   // Fy
  EXPECT_GT(count_colour(inside, {220, 90, 30}, 20), area.width / 2);   // Fz
  // Fy = -0.2 N is constant: its pixels lie on one row (anti-aliasing
  // spreads a 2 px line over ~4 rows).
  cv::Mat fy;
  cv::inRange(inside, cv::Scalar(20, 140, 20), cv::Scalar(60, 180, 60), fy);
  std::vector<cv::Point> pts;
  cv::findNonZero(fy, pts);
  ASSERT_FALSE(pts.empty());
  int ymin = pts[0].y, ymax = pts[0].y;
  for (const auto& p : pts) {
    ymin = std::min(ymin, p.y);
    ymax = std::max(ymax, p.y);
  }
  // The legend swatch is outside `inside`; the curve is flat.
  EXPECT_LE(ymax - ymin, 4);
  // Nothing written for mismatched inputs.
  EXPECT_THROW(write_force_plot(path.parent_path() / "bad.png", {0.0, 1.0}, {Vec3::Zero()}), Error);
  EXPECT_FALSE(fs::exists(path.parent_path() / "bad.png"));
}

TEST(ContactSheet, EvenlySpacedFramesIncludeFirstAndLast) {
  EXPECT_EQ(contact_sheet_frames(31, 4), (std::vector<int>{0, 10, 20, 30}));
  EXPECT_EQ(contact_sheet_frames(3, 6), (std::vector<int>{0, 1, 2}));  // fewer frames than tiles
  EXPECT_EQ(contact_sheet_frames(10, 1), (std::vector<int>{0}));
}

TEST(ContactSheet, GridOfTilesWithBordersAndTimestamps) {
  std::vector<cv::Mat> tiles;
  for (int i = 0; i < 5; ++i) {
    // Flat frames of distinct shades; a timestamp box drawn on each.
    cv::Mat frame(240, 320, CV_8UC3, cv::Scalar(200 - 30 * i, 120, 30 * i));
    tiles.push_back(make_contact_sheet_tile(frame, 0.25 * i, 160));
  }
  ASSERT_EQ(tiles[0].cols, 160);
  ASSERT_EQ(tiles[0].rows, 120);
  const cv::Mat sheet = compose_contact_sheet(tiles, 3);
  EXPECT_EQ(sheet.cols, 3 * 160);
  EXPECT_EQ(sheet.rows, 2 * 120);
  for (int i = 0; i < 6; ++i) {
    const cv::Mat cell = sheet(cv::Rect((i % 3) * 160, (i / 3) * 120, 160, 120));
    if (i == 5) {
      // The empty cell stays mid grey.
      EXPECT_EQ(count_colour(cell, {128, 128, 128}, 0), 160 * 120);
      continue;
    }
    // Border: the tile's outermost columns and rows are the dark border colour.
    EXPECT_GE(count_colour(cell.col(0), {60, 60, 60}, 5), 115) << i;
    EXPECT_GE(count_colour(cell.col(159), {60, 60, 60}, 5), 115) << i;
    EXPECT_GE(count_colour(cell.row(119), {60, 60, 60}, 5), 155) << i;
    // Timestamp: a light label box with dark text in the top-left corner.
    const cv::Mat label = cell(cv::Rect(4, 4, 70, 16));
    EXPECT_GT(count_colour(label, {245, 245, 245}, 3), 200) << i;
    EXPECT_GT(count_colour(label, {20, 20, 20}, 60), 30) << i;
    // The body of the tile is the frame's shade.
    const cv::Vec3b body = cell.at<cv::Vec3b>(80, 100);
    EXPECT_EQ(body, cv::Vec3b(200 - 30 * i, 120, 30 * i)) << i;
  }
  // Different timestamps render differently.
  EXPECT_GT(cv::norm(sheet(cv::Rect(4, 4, 70, 16)), sheet(cv::Rect(164, 4, 70, 16)), cv::NORM_L1), 0.0);
}

}  // namespace
}  // namespace plots_test
}  // namespace organsim

namespace organsim {
namespace plots_test {
namespace {

// A backend whose reaction comes one tick late, like the GL backend's.
class LateBackend : public Backend {
 public:
  std::string name() const override { return "late"; }
  std::string device() const override { return "test"; }
  std::string precision() const override { return "double"; }
  Plan plan() const override { return {}; }
  const StepPlan& step_plan() const override { return plan_; }
  int32_t reaction_latency_ticks() const override { return 1; }
  Reaction tick(const TickRequest&) override { return {}; }
  void attach(const Attachment&) override {}
  void release() override {}
  std::unique_ptr<PreparedModel> prepare(const Model& next) const override {
    return std::make_unique<PreparedModel>(next);
  }
  void adopt(std::unique_ptr<PreparedModel>) override {}
  void positions(std::vector<Vec3>&) const override {}
  void set_state(const std::vector<Vec3>&, const std::vector<Vec3>&) override {}
  double time() const override { return 0; }

 private:
  StepPlan plan_;
};

TEST(ForcePlotRecorder, ShiftsLateReactionsToTheTickTheyBelongTo) {
  const fs::path path = fs::path(ORGANSIM_TEST_TMP) / "plots" / "late_forces.png";
  fs::remove(path);
  ForcePlotRecorder recorder(path, 1e-3, 100);
  LateBackend backend;
  Model model;
  recorder.on_start(model, backend);
  // Tick i returns the reaction of tick i - 1: a step from 0 to 2 N that
  // happened at tick 50 (t = 0.051 s) arrives at tick 51.
  for (int i = 0; i < 100; ++i) {
    TickInfo info;
    info.tick = i;
    info.t = (i + 1) * 1e-3;
    info.reaction.force = Vec3(0, 0, i >= 51 ? 2.0 : 0.0);
    recorder.on_tick(model, backend, info);
  }
  recorder.on_finish(model, backend);
  const cv::Mat img = cv::imread(path.string());
  ASSERT_FALSE(img.empty());
  // The rise of Fz (blue) is at t = 0.051 s, not 0.052 s: find the first
  // column of the plot area with a blue pixel above the zero line.
  const cv::Rect area = force_plot_area(900, 500);
  cv::Mat blue;
  cv::inRange(img(area), cv::Scalar(180, 60, 10), cv::Scalar(255, 120, 60), blue);
  int first_high = -1;
  for (int x = 0; x < area.width && first_high < 0; ++x) {
    // "High": in the upper half of the plot (2 N is the top of the axis).
    if (cv::countNonZero(blue(cv::Rect(x, 0, 1, area.height / 2))) > 0) first_high = x;
  }
  ASSERT_GE(first_high, 0);
  // Time axis 0.001 .. 0.099 s rounded out to 0 .. 0.1 s. The curve rises
  // from (0.050 s, 0) to (0.051 s, 2 N): it enters the upper half at
  // 0.0505 s, 50.5 % of the width (the 2 px line starts ~1 px earlier). A
  // one-tick error would move it by 1 % = ~6.7 px.
  EXPECT_NEAR(first_high, 0.505 * area.width, 3.0);
}

}  // namespace
}  // namespace plots_test
}  // namespace organsim
