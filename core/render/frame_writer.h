#pragma once
// Encodes and writes rendered frames on a background thread, so the run loop
// only pays for drawing and read-back: PNG files, the video stream and the
// contact sheet's tiles. Errors on the writer thread are rethrown by the next
// submit() or by finish().
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "core/render/frame_options.h"
#include "core/render/video_sink.h"

namespace organsim {

struct FrameWriterTiming {
  int frames = 0;
  double encode_ms_total = 0;  // PNG + video + tile per frame, on the writer thread
};

class FrameWriter {
 public:
  // outdir: PNGs go to outdir/frames/frame_00000.png when outputs.frames->write_png;
  // video and contact sheet paths are relative to outdir. `expected_frames`
  // (>= 1) picks the contact sheet's evenly spaced frames.
  FrameWriter(const FrameOutputs& outputs, const std::filesystem::path& outdir, int expected_frames,
              cv::Size frame_size);
  ~FrameWriter();  // joins; leaves no temporary files
  FrameWriter(const FrameWriter&) = delete;
  FrameWriter& operator=(const FrameWriter&) = delete;

  // Queues frame `index` (0, 1, ...) at simulated time t (s). Blocks while
  // `max_queued` frames are waiting, so memory stays bounded.
  void submit(int index, double t, cv::Mat bgr);
  // Waits for the queue, closes the video and writes the contact sheet.
  void finish();
  FrameWriterTiming timing() const;

  static constexpr size_t max_queued = 8;

 private:
  struct Job {
    int index;
    double t;
    cv::Mat image;
  };
  void run();
  void write(const Job& job);
  void rethrow_if_failed();

  FrameOutputs outputs_;
  std::filesystem::path outdir_;
  std::unique_ptr<VideoSink> video_;
  std::vector<int> sheet_frames_;
  std::vector<cv::Mat> sheet_tiles_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Job> queue_;
  bool closing_ = false;
  bool finished_ = false;
  std::exception_ptr error_;
  FrameWriterTiming timing_;
  std::thread thread_;
};

// Frames a run of `duration` seconds yields at `rate` per second, counting
// the one at t = 0.
int expected_frame_count(double duration, double rate);

}  // namespace organsim
