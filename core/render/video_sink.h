#pragma once
// A video file written frame by frame through cv::VideoWriter (FFmpeg
// backend), under a temporary name with the same extension, renamed when
// finished: a failed run leaves no half-written video under the final name.
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace cv {
class VideoWriter;
}

namespace organsim {

class VideoSink {
 public:
  // codec: a FOURCC such as "mp4v" (MPEG-4 part 2) or "avc1" (H.264); fps:
  // playback frames per second. Throws Error(Output) when OpenCV cannot open
  // a writer for this codec and container.
  VideoSink(const std::filesystem::path& path, const std::string& codec, double fps, cv::Size size);
  ~VideoSink();  // without finish(): removes the temporary file
  VideoSink(const VideoSink&) = delete;
  VideoSink& operator=(const VideoSink&) = delete;

  void write(const cv::Mat& bgr);  // must have the size given above
  void finish();                   // closes and renames to the final path
  int frames() const { return frames_; }

 private:
  std::filesystem::path path_, temporary_;
  std::unique_ptr<cv::VideoWriter> writer_;
  cv::Size size_;
  int frames_ = 0;
  bool finished_ = false;
};

}  // namespace organsim
