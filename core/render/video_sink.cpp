#include "core/render/video_sink.h"

#include <opencv2/videoio.hpp>
#include <unistd.h>

#include "core/util/error.h"

namespace organsim {

namespace fs = std::filesystem;

VideoSink::VideoSink(const fs::path& path, const std::string& codec, double fps, cv::Size size)
    : path_(path), size_(size) {
  if (codec.size() != 4) {
    throw Error(ErrorKind::Scenario, "video.codec: expected a four-character code such as \"mp4v\", got \"" + codec + "\"");
  }
  if (!(fps > 0)) throw Error(ErrorKind::Scenario, "video.fps: expected a positive number of frames per second");
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  // Same directory and extension (the extension picks the container).
  std::string name(".");
  name.append(path.stem().string()).append(".tmp").append(std::to_string(::getpid()));
  name.append(path.extension().string());
  temporary_ = path;
  temporary_.replace_filename(name);
  writer_ = std::make_unique<cv::VideoWriter>();
  const int fourcc = cv::VideoWriter::fourcc(codec[0], codec[1], codec[2], codec[3]);
  bool ok = false;
  try {
    ok = writer_->open(temporary_.string(), cv::CAP_FFMPEG, fourcc, fps, size, true);
  } catch (const cv::Exception&) {
    ok = false;  // reported below with the file and codec
  }
  if (!ok) {
    std::error_code ignored;
    fs::remove(temporary_, ignored);
    throw Error(ErrorKind::Output, path.string() + ": OpenCV (FFmpeg) cannot write codec \"" + codec + "\" into a " +
                                       path.extension().string() + " file; mp4v and avc1 in .mp4 work on Debian 12");
  }
}

VideoSink::~VideoSink() {
  if (!finished_) {
    writer_->release();
    std::error_code ignored;
    fs::remove(temporary_, ignored);
  }
}

void VideoSink::write(const cv::Mat& bgr) {
  if (bgr.size() != size_ || bgr.type() != CV_8UC3) {
    throw Error(ErrorKind::Output, path_.string() + ": frame of a different size or type than the video");
  }
  writer_->write(bgr);
  ++frames_;
}

void VideoSink::finish() {
  writer_->release();
  std::error_code ec;
  fs::rename(temporary_, path_, ec);
  if (ec) throw Error(ErrorKind::Output, path_.string() + ": cannot rename from " + temporary_.string() + ": " + ec.message());
  finished_ = true;
}

}  // namespace organsim
