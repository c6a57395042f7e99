// The video writer's failures: a codec FFmpeg cannot write into the
// container, and a frame of the wrong size. Each is an output error naming
// the file, and neither leaves a file under the final name or a temporary.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/videoio.hpp>

#include "core/render/video_sink.h"
#include "core/util/error.h"
#include "tests/core/mesh_io_test_util.h"

namespace organsim {
namespace video_sink_test {
namespace {

namespace fs = std::filesystem;


TEST(VideoSink, ACodecTheContainerCannotTakeIsAnOutputErrorAndLeavesNothing) {
  const fs::path dir = testing::fresh_test_dir("render");
  try {
    VideoSink sink(dir / "v.mp4", "zzzz", 10, {64, 48});
    FAIL() << "an unknown codec was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Output);
    EXPECT_NE(std::string(e.what()).find((dir / "v.mp4").string() + ": OpenCV (FFmpeg) cannot write codec \"zzzz\""),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::is_empty(dir));
  // A code that is not four characters is the scenario's fault.
  try {
    VideoSink sink(dir / "v.mp4", "h264x", 10, {64, 48});
    FAIL() << "a five-character codec was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::Scenario);
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

TEST(VideoSink, AFrameOfAnotherSizeIsRefusedAndTheUnfinishedVideoRemoved) {
  const fs::path dir = testing::fresh_test_dir("render");
  {
    VideoSink sink(dir / "v.mp4", "mp4v", 10, {64, 48});
    sink.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(0, 0, 255)));
    try {
      sink.write(cv::Mat(40, 64, CV_8UC3, cv::Scalar(0, 0, 255)));
      FAIL() << "a 64x40 frame went into a 64x48 video";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::Output);
      EXPECT_NE(std::string(e.what()).find("frame of a different size or type than the video"), std::string::npos);
    }
    EXPECT_THROW(sink.write(cv::Mat(48, 64, CV_8UC1, cv::Scalar(0))), Error);  // grey, not BGR
    EXPECT_EQ(sink.frames(), 1);
  }  // destroyed without finish(): the run failed
  EXPECT_TRUE(fs::is_empty(dir)) << "a half-written video was left";
}

TEST(VideoSink, AFinishedVideoHasItsFramesUnderTheFinalName) {
  const fs::path dir = testing::fresh_test_dir("render");
  VideoSink sink(dir / "v.mp4", "mp4v", 10, {64, 48});
  for (int i = 0; i < 3; ++i) sink.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(0, 80 * i, 255)));
  sink.finish();
  cv::VideoCapture video((dir / "v.mp4").string(), cv::CAP_FFMPEG);
  ASSERT_TRUE(video.isOpened());
  int frames = 0;
  cv::Mat frame;
  while (video.read(frame)) ++frames;
  EXPECT_EQ(frames, 3);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace video_sink_test
}  // namespace organsim
