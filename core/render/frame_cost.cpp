#include "core/render/frame_cost.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <unistd.h>

#include "core/gl/egl_context.h"
#include "core/gl/gl_api.h"
#include "core/mesh/boundary.h"
#include "core/render/surface_renderer.h"
#include "core/render/video_sink.h"

namespace organsim {

namespace {
using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}
}  // namespace

FrameCost measure_frame_cost(const Model& model, int width, int height, int frames) {
  gl::EglContext context;
  SurfaceRenderer renderer(width, height);
  const std::vector<Tri> faces = extract_boundary_faces(model.tet_points);
  renderer.set_faces(faces, model.npoint());
  const Camera camera = make_camera(CameraOptions{}, model.rest_position, static_cast<double>(width) / height);
  StyleOptions style;
  ToolDraw tool;
  tool.visible = true;
  tool.a = tool.b = model.rest_position.empty() ? Vec3::Zero() : model.rest_position[0];
  tool.radius = 0.01;

  // The video goes to a temporary file that is removed afterwards.
  const std::filesystem::path video_path = std::filesystem::temp_directory_path() /
                                           ("organsim_frame_cost_" + std::to_string(::getpid()) + ".mp4");
  std::vector<double> upload, render, readback, png, video;
  {
    VideoSink sink(video_path, "mp4v", 30, cv::Size(width, height));
    std::vector<Vec3> x = model.rest_position;
    for (int i = 0; i <= frames; ++i) {
      // Move the points a little so every upload and frame is different.
      for (Vec3& p : x) p.z() += 1e-6;
      auto start = Clock::now();
      renderer.set_positions(x);
      const double u = ms_since(start);
      start = Clock::now();
      renderer.draw(camera, style, tool);
      glFinish();
      const double r = ms_since(start);
      start = Clock::now();
      const cv::Mat image = renderer.read_back();
      const double b = ms_since(start);
      start = Clock::now();
      std::vector<uchar> encoded;
      cv::imencode(".png", image, encoded);
      const double p = ms_since(start);
      start = Clock::now();
      sink.write(image);
      const double v = ms_since(start);
      if (i == 0) continue;  // warm-up: shader compilation, first allocations
      upload.push_back(u);
      render.push_back(r);
      readback.push_back(b);
      png.push_back(p);
      video.push_back(v);
    }
    // Not finished: the destructor removes the temporary video.
  }
  FrameCost cost;
  cost.frames = frames;
  cost.width = width;
  cost.height = height;
  cost.triangles = faces.size();
  cost.renderer = context.renderer();
  cost.upload_ms = median(upload);
  cost.render_ms = median(render);
  cost.readback_ms = median(readback);
  cost.png_ms = median(png);
  cost.video_ms = median(video);
  return cost;
}

}  // namespace organsim
