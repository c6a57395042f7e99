// The whole frame path: CPU backend + frame recorder (GL render, read-back,
// writer thread) -> PNG sequence, mp4 video and contact sheet, checked by
// their content. A slab fixed at the bottom is pressed by the tool in its
// middle: frames must change around the contact and nowhere far from it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/model/model.h"
#include "core/render/camera.h"
#include "core/render/frame_recorder.h"
#include "core/sim/cpu_backend.h"
#include "tests/render/render_test_util.h"

namespace organsim {
namespace frame_recorder_test {
namespace {

namespace fs = std::filesystem;
using testing::differs_from;
using testing::project;

struct PressRun {
  fs::path outdir;
  Model model;
  ToolSpec tool;
  FrameOutputs outputs;
  double duration = 0.2;  // s
  int ticks_run = 0;
};

constexpr double kTop = 0.04;     // slab top, m
constexpr double kRadius = 0.015; // tool radius, m

PressRun run_press(const std::string& name) {
  PressRun run;
  // ctest runs each test of the suite in its own process, in parallel: the
  // shared run needs a folder per process or they delete each other's frames.
  run.outdir = fs::path(ORGANSIM_TEST_TMP) / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(run.outdir);
  run.model = testing::pressed_slab_model(10, kTop);

  // From 5 mm above the top to 8 mm into it over 0.1 s, then held.
  run.tool.radius = kRadius;
  run.tool.contact_stiffness = 500;
  run.tool.keyframes = {{0.0, Vec3(0, 0, kTop + kRadius + 0.005)}, {0.1, Vec3(0, 0, kTop + kRadius - 0.008)}};
  BackendTool backend_tool;
  backend_tool.present = true;
  backend_tool.radius = kRadius;
  backend_tool.contact_stiffness = run.tool.contact_stiffness;
  auto backend = make_cpu_backend(run.model, backend_tool);

  FramesOptions frames;
  frames.rate = 20;  // 5 frames over 0.2 s: t = 0, 0.05, ..., 0.2
  frames.width = 320;
  frames.height = 240;
  run.outputs.frames = frames;
  run.outputs.video = VideoOptions{"press.mp4", "mp4v", 10};
  run.outputs.contact_sheet = ContactSheetOptions{"sheet.png", 4, 2, 160};
  auto recorder = make_frame_recorder(run.outputs, run.outdir, run.duration, run.tool);
  EXPECT_NE(recorder, nullptr);

  TickRequest request;
  request.dt = 1e-4;
  request.substeps = 10;
  request.tool_active = true;
  recorder->on_start(run.model, *backend);
  const int ticks = static_cast<int>(std::lround(run.duration / (request.dt * request.substeps)));
  for (int i = 0; i < ticks; ++i) {
    const double t0 = i * 1e-3, t1 = (i + 1) * 1e-3;
    request.tool_from = run.tool.position_at(t0);
    request.tool_to = run.tool.position_at(t1);
    TickInfo info;
    info.tick = i;
    info.reaction = backend->tick(request);
    info.t = backend->time();
    info.tool_center = request.tool_to;
    info.tool_active = true;
    recorder->on_tick(run.model, *backend, info);
    ++run.ticks_run;
  }
  recorder->on_finish(run.model, *backend);
  const FrameRecorderTiming timing = recorder->timing();
  EXPECT_EQ(timing.frames, 5);
  std::cout << "per frame: render " << timing.render_ms / timing.frames << " ms, read-back "
            << timing.readback_ms / timing.frames << " ms, encode " << timing.encode_ms / timing.frames << " ms\n";
  return run;
}

class FrameRecorderPress : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { run_ = new PressRun(run_press("press")); }
  static void TearDownTestSuite() { delete run_; }
  static PressRun* run_;
};
PressRun* FrameRecorderPress::run_ = nullptr;

TEST_F(FrameRecorderPress, WritesOnePngPerFrameAtTheRequestedSize) {
  for (int i = 0; i < 5; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", i);
    const cv::Mat img = cv::imread((run_->outdir / "frames" / name).string());
    ASSERT_FALSE(img.empty()) << name;
    EXPECT_EQ(img.cols, 320);
    EXPECT_EQ(img.rows, 240);
  }
  EXPECT_FALSE(fs::exists(run_->outdir / "frames" / "frame_00005.png"));
  // No temporary files left behind.
  for (const auto& entry : fs::recursive_directory_iterator(run_->outdir)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

TEST_F(FrameRecorderPress, PressedFrameDiffersAroundTheContactOnly) {
  const cv::Mat rest = cv::imread((run_->outdir / "frames" / "frame_00000.png").string());
  const cv::Mat pressed = cv::imread((run_->outdir / "frames" / "frame_00004.png").string());
  ASSERT_FALSE(rest.empty());
  ASSERT_FALSE(pressed.empty());
  // The slab is in the picture: object pixels (non-white) are a good share.
  EXPECT_GT(cv::countNonZero(differs_from(rest, {255, 255, 255}, 8)), 320 * 240 / 10);

  cv::Mat diff;
  cv::absdiff(rest, pressed, diff);
  cv::Mat grey;
  cv::cvtColor(diff, grey, cv::COLOR_BGR2GRAY);
  const cv::Mat changed = grey > 24;  // beyond shading noise of far-field micro-motion

  // "Around the contact": the image of a 4.5 cm ball around the contact point
  // (tool radius 1.5 cm + its 1.3 cm travel + the dimple's spread).
  const Camera cam = make_camera(run_->outputs.frames->camera, run_->model.rest_position, 320.0 / 240.0);
  cv::Mat near(240, 320, CV_8U, cv::Scalar(0));
  std::vector<cv::Point> hull_pts;
  for (int i = 0; i < 200; ++i) {
    const double u = std::acos(1 - 2 * (i + 0.5) / 200), v = i * 2.399963;
    const Vec3 p = Vec3(0, 0, kTop) + 0.045 * Vec3(std::sin(u) * std::cos(v), std::sin(u) * std::sin(v), std::cos(u));
    const cv::Point2d px = project(cam, p, 320, 240);
    hull_pts.emplace_back(static_cast<int>(px.x), static_cast<int>(px.y));
  }
  std::vector<cv::Point> hull;
  cv::convexHull(hull_pts, hull);
  cv::fillConvexPoly(near, hull, 255);
  cv::Mat far;
  cv::bitwise_not(near, far);

  const int changed_near = cv::countNonZero(changed & near);
  const int changed_far = cv::countNonZero(changed & far);
  std::cout << "changed pixels near the contact " << changed_near << ", far " << changed_far << "\n";
  // The tool moved by 1.3 cm and dented the slab: hundreds of pixels change.
  EXPECT_GT(changed_near, 300);
  // Far away the slab barely moves: fewer than 0.2 % of the far pixels change.
  EXPECT_LT(changed_far, cv::countNonZero(far) / 500);
}

TEST_F(FrameRecorderPress, VideoReadsBackWithFrameCountAndSize) {
  cv::VideoCapture video((run_->outdir / "press.mp4").string(), cv::CAP_FFMPEG);
  ASSERT_TRUE(video.isOpened());
  int count = 0;
  cv::Mat frame, first;
  while (video.read(frame)) {
    EXPECT_EQ(frame.cols, 320);
    EXPECT_EQ(frame.rows, 240);
    if (count == 0) first = frame.clone();
    ++count;
  }
  EXPECT_EQ(count, 5);
  // Lossy, but the content is the first PNG's: mean absolute error < 8 levels.
  const cv::Mat png = cv::imread((run_->outdir / "frames" / "frame_00000.png").string());
  ASSERT_FALSE(first.empty());
  EXPECT_LT(cv::norm(first, png, cv::NORM_L1) / (320.0 * 240 * 3), 8.0);
}

TEST_F(FrameRecorderPress, ContactSheetHasTheRequestedGrid) {
  const cv::Mat sheet = cv::imread((run_->outdir / "sheet.png").string());
  ASSERT_FALSE(sheet.empty());
  // 4 frames in 2 columns of 160 x 120 tiles (320 x 240 frames halved).
  EXPECT_EQ(sheet.cols, 2 * 160);
  EXPECT_EQ(sheet.rows, 2 * 120);
  for (int i = 0; i < 4; ++i) {
    const cv::Mat cell = sheet(cv::Rect((i % 2) * 160, (i / 2) * 120, 160, 120));
    // Border column of dark grey (60) and a light timestamp box.
    cv::Mat border;
    cv::inRange(cell.col(0), cv::Scalar(50, 50, 50), cv::Scalar(70, 70, 70), border);
    EXPECT_GE(cv::countNonZero(border), 110) << i;
    cv::Mat box;
    cv::inRange(cell(cv::Rect(4, 4, 60, 14)), cv::Scalar(240, 240, 240), cv::Scalar(250, 250, 250), box);
    EXPECT_GT(cv::countNonZero(box), 150) << i;
  }
  // First tile (t = 0, tool above) and last (pressed) differ.
  EXPECT_GT(cv::norm(sheet(cv::Rect(0, 20, 160, 100)), sheet(cv::Rect(160, 140, 160, 100)), cv::NORM_L1), 1000.0);
}

TEST(FrameRecorder, NoOutputsMakeNoRecorder) {
  EXPECT_EQ(make_frame_recorder(FrameOutputs{}, ORGANSIM_TEST_TMP, 1.0, std::nullopt), nullptr);
}

}  // namespace
}  // namespace frame_recorder_test
}  // namespace organsim
