#include "core/render/frame_writer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/render/contact_sheet.h"
#include "core/render/image_io.h"
#include "core/util/error.h"

namespace organsim {

namespace fs = std::filesystem;

int expected_frame_count(double duration, double rate) {
  // 1e-9 absorbs rounding in duration * rate (e.g. 1.0 s at 30 fps).
  return static_cast<int>(std::floor(std::max(duration, 0.0) * rate + 1e-9)) + 1;
}

FrameWriter::FrameWriter(const FrameOutputs& outputs, const fs::path& outdir, int expected_frames,
                         cv::Size frame_size)
    : outputs_(outputs), outdir_(outdir) {
  if (outputs_.video) {
    video_ = std::make_unique<VideoSink>(outdir_ / outputs_.video->file, outputs_.video->codec, outputs_.video->fps,
                                         frame_size);
  }
  if (outputs_.contact_sheet) {
    if (outputs_.contact_sheet->frames < 1) throw Error(ErrorKind::Scenario, "contact_sheet.frames: expected at least 1");
    if (outputs_.contact_sheet->columns < 1) throw Error(ErrorKind::Scenario, "contact_sheet.columns: expected at least 1");
    sheet_frames_ = contact_sheet_frames(std::max(expected_frames, 1), outputs_.contact_sheet->frames);
  }
  if (outputs_.frames && outputs_.frames->write_png) fs::create_directories(outdir_ / "frames");
  thread_ = std::thread([this] { run(); });
}

FrameWriter::~FrameWriter() {
  {
    std::lock_guard lock(mutex_);
    closing_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FrameWriter::rethrow_if_failed() {
  if (error_) std::rethrow_exception(error_);
}

void FrameWriter::submit(int index, double t, cv::Mat bgr) {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return queue_.size() < max_queued || error_; });
  rethrow_if_failed();
  queue_.push_back({index, t, std::move(bgr)});
  changed_.notify_all();
}

void FrameWriter::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return !queue_.empty() || closing_; });
      if (queue_.empty()) return;  // closing and drained
      job = std::move(queue_.front());
    }
    const auto start = std::chrono::steady_clock::now();
    std::exception_ptr failure;
    try {
      write(job);
    } catch (...) {
      failure = std::current_exception();
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::lock_guard lock(mutex_);
    queue_.pop_front();
    ++timing_.frames;
    timing_.encode_ms_total += ms;
    if (failure && !error_) error_ = failure;
    changed_.notify_all();
    if (error_) {
      queue_.clear();
      return;
    }
  }
}

void FrameWriter::write(const Job& job) {
  if (outputs_.frames && outputs_.frames->write_png) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", job.index);
    write_image_atomically(outdir_ / "frames" / name, job.image);
  }
  if (video_) video_->write(job.image);
  if (std::find(sheet_frames_.begin(), sheet_frames_.end(), job.index) != sheet_frames_.end()) {
    sheet_tiles_.push_back(make_contact_sheet_tile(job.image, job.t, outputs_.contact_sheet->tile_width));
  }
}

void FrameWriter::finish() {
  {
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.empty() || error_; });
    rethrow_if_failed();
    if (finished_) return;
    finished_ = true;
  }
  // The writer thread is idle now (queue empty), so its state is ours.
  if (video_) video_->finish();
  if (outputs_.contact_sheet && !sheet_tiles_.empty()) {
    write_image_atomically(outdir_ / outputs_.contact_sheet->file,
                           compose_contact_sheet(sheet_tiles_, outputs_.contact_sheet->columns));
  }
}

FrameWriterTiming FrameWriter::timing() const {
  std::lock_guard lock(mutex_);
  return timing_;
}

}  // namespace organsim
