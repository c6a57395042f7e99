#include "core/render/frame_recorder.h"

#include <EGL/egl.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/gl/egl_context.h"
#include "core/gl/gl_backend.h"
#include "core/gl/gl_api.h"
#include "core/mesh/boundary.h"
#include "core/render/colormap.h"
#include "core/render/colormap_range.h"
#include "core/render/frame_writer.h"
#include "core/render/label_colors.h"
#include "core/render/surface_renderer.h"
#include "core/util/error.h"

namespace organsim {

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Remembers the thread's current EGL context and puts it back at the end of
// the scope (the GL backend's, or none), so the simulation never sees its
// context switched under it.
class SavedContext {
 public:
  SavedContext()
      : display_(eglGetCurrentDisplay()),
        context_(eglGetCurrentContext()),
        draw_(eglGetCurrentSurface(EGL_DRAW)),
        read_(eglGetCurrentSurface(EGL_READ)) {}
  ~SavedContext() {
    if (context_ != EGL_NO_CONTEXT) {
      eglMakeCurrent(display_, draw_, read_, context_);
    } else if (eglGetCurrentContext() != EGL_NO_CONTEXT) {
      eglMakeCurrent(eglGetCurrentDisplay(), EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    }
  }
  SavedContext(const SavedContext&) = delete;
  SavedContext& operator=(const SavedContext&) = delete;

 private:
  EGLDisplay display_;
  EGLContext context_;
  EGLSurface draw_, read_;
};

// The recorder's context, current for a scope.
class ContextScope {
 public:
  explicit ContextScope(const gl::EglContext& context) { context.make_current(); }

 private:
  SavedContext saved_;  // constructed before the body runs: saves the previous context
};

}  // namespace

struct FrameRecorder::Impl {
  FrameOutputs outputs;
  FramesOptions frames;
  std::filesystem::path outdir;
  double duration = 0;
  std::optional<ToolSpec> tool;

  std::unique_ptr<gl::EglContext> context;
  const GlBackend* gl_backend = nullptr;  // set when drawing straight from its storage buffer
  std::unique_ptr<SurfaceRenderer> renderer;
  std::unique_ptr<FrameWriter> writer;
  Camera camera;
  int written = 0;    // frames submitted (file numbering)
  int next_due = 0;   // frame k is due at t = k / rate
  std::vector<Vec3> positions;  // internal numbering, reused between frames
  std::vector<float> scalars;
  std::vector<Vec3f> colors;
  std::vector<Vec3> start_positions;  // positions at t = 0 (settled), internal numbering
  std::vector<int32_t> labels;  // the model's labels, ascending, for the label key
  ColormapRange range;      // fixed for the run once known
  FrameRecorderTiming timing;

  void render_frame(const Model& model, Backend& backend, double t, const Vec3& tool_center, const Quat& tool_turn) {
    // A scale over per-point values; labels are per face and set with the faces.
    const bool colormap = frames.style.colormap == Colormap::Strain || frames.style.colormap == Colormap::Displacement;
    auto start = Clock::now();
    // Positions first, while the simulation's context (if any) is current:
    // a GL backend makes its own context current to read them back.
    // Drawing straight from the GL buffer needs them only for the colour map.
    if (!gl_backend || colormap) backend.positions(positions);
    GLsync sim_done = nullptr;
    if (gl_backend) {
      gl_backend->context().make_current();
      // In the simulation's context: make its compute writes to x_t visible
      // to our vertex shader and fence them, so our context waits on the GPU
      // for them (no CPU stall, no copy).
      glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
      sim_done = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
      glFlush();
    }
    ContextScope scope(*context);
    if (gl_backend) {
      glWaitSync(sim_done, 0, GL_TIMEOUT_IGNORED);
      glDeleteSync(sim_done);
      renderer->use_position_buffer(gl_backend->position_buffer(), 4, 0);
    } else {
      renderer->set_positions(positions);
    }
    double colormap_max = 0;
    if (colormap) {
      if (frames.style.colormap == Colormap::Strain) {
        point_strain(model, positions, scalars);
      } else {
        point_displacement(start_positions, positions, scalars);  // what happened since t = 0
      }
      // One range for the whole run, so a colour means the same value in every
      // frame and on the contact sheet; values above it saturate.
      if (!(range.max > 0)) range.max = colormap_range_max(scalars, 0);
      colormap_max = range.max;
      colors.resize(scalars.size());
      for (size_t i = 0; i < scalars.size(); ++i) {
        // An all-zero field (the rest state) is the bottom of the scale.
        colors[i] = colormap_rgb(colormap_max > 0 ? static_cast<float>(scalars[i] / colormap_max) : 0.0f);
      }
      renderer->set_point_colors(colors);
    }
    const double upload_ms = ms_since(start);

    start = Clock::now();
    ToolDraw draw_tool;
    if (tool) {
      const ToolPlacement placed = place_tool(tool->backend_tool(), tool_center, tool_turn, tool->gap_at(t));
      draw_tool = {true, placed.a, placed.b, placed.radius, placed.jaws, placed.a2, placed.b2};
    }
    renderer->draw(camera, frames.style, draw_tool);
    glFinish();  // so render and read-back are timed apart
    timing.render_ms += ms_since(start);

    start = Clock::now();
    cv::Mat image = renderer->read_back();
    if (frames.style.colormap == Colormap::Label) {
      draw_label_key(image, labels);
    } else if (colormap) {
      draw_colormap_legend(image, colormap_legend_title(frames.style.colormap, range), 0.0, colormap_max,
                           colormap_unit(frames.style.colormap));
    }
    timing.readback_ms += ms_since(start) + upload_ms;
    writer->submit(written, t, std::move(image));
    ++timing.frames;
    ++written;
    // A frame rendered at t satisfies every due time up to t; frames due
    // faster than ticks are skipped, not rendered twice.
    next_due = static_cast<int>(std::floor(t * frames.rate + 1e-9)) + 1;
  }
};

FrameRecorder::FrameRecorder(const FrameOutputs& outputs, const std::filesystem::path& outdir, double duration,
                             std::optional<ToolSpec> tool)
    : impl_(std::make_unique<Impl>()) {
  if (!outputs.frames) throw Error(ErrorKind::Scenario, "outputs: video and contact_sheet need outputs.frames");
  if (!(outputs.frames->rate > 0)) throw Error(ErrorKind::Scenario, "outputs.frames.rate: expected > 0 frames per second");
  impl_->outputs = outputs;
  impl_->frames = *outputs.frames;
  impl_->outdir = outdir;
  impl_->duration = duration;
  impl_->tool = std::move(tool);
}

FrameRecorder::~FrameRecorder() {
  if (impl_->context) {
    // GL objects die in their own context.
    ContextScope scope(*impl_->context);
    impl_->renderer.reset();
  }
}

void FrameRecorder::topology_changed(const Model& model) {
  Impl& s = *impl_;
  ContextScope scope(*s.context);
  std::vector<int32_t> face_tet;
  const std::vector<Tri> faces = extract_boundary_faces(model.tet_points, &face_tet);
  s.renderer->set_faces(faces, model.npoint());
  if (s.frames.style.colormap != Colormap::Label) return;
  // Labels follow the tets through every rebuild, so the faces a cut opens
  // take the colour of the tets they belong to, and the lines where two
  // labels meet on the new surface are found again.
  const std::vector<int32_t> label_of_face = face_labels(model, face_tet);
  std::vector<Vec3f> colors(faces.size());
  for (size_t f = 0; f < faces.size(); ++f) colors[f] = label_rgb(label_of_face[f]);
  s.renderer->set_face_colors(colors);
  s.renderer->set_lines(edges_between_face_groups(faces, label_of_face));
  s.labels = model.tet_label.empty() ? std::vector<int32_t>{0} : model.tet_label;
  std::sort(s.labels.begin(), s.labels.end());
  s.labels.erase(std::unique(s.labels.begin(), s.labels.end()), s.labels.end());
}

void FrameRecorder::on_topology_changed(const Model& next, Backend& /*backend*/) { topology_changed(next); }

void FrameRecorder::on_start(const Model& model, Backend& backend) {
  Impl& s = *impl_;
  // Before our context exists: a GL backend makes its own current to read back.
  backend.positions(s.start_positions);
  // Created here, not in the constructor, so `--plan` and scenes that fail
  // before the run never open a GL context.
  {
    SavedContext saved;  // creating a context makes it current
    gl::EglContextOptions options;
    // With the GL backend, share its objects so the renderer reads the
    // simulation's position buffer directly.
    s.gl_backend = dynamic_cast<const GlBackend*>(&backend);
    if (s.gl_backend) options.share = &s.gl_backend->context();
    s.context = std::make_unique<gl::EglContext>(options);
  }
  {
    ContextScope scope(*s.context);
    s.renderer = std::make_unique<SurfaceRenderer>(s.frames.width, s.frames.height);
  }
  topology_changed(model);
  std::vector<Vec3> tool_path;
  constexpr int kPathSamples = 50;
  for (int k = 0; s.tool && k <= kPathSamples; ++k) tool_path.push_back(s.tool->position_at(s.duration * k / kPathSamples));
  s.camera = make_run_camera(s.frames.camera, s.start_positions, tool_path,
                             s.tool ? s.tool->radius + s.tool->extent() : 0.0,
                             static_cast<double>(s.frames.width) / s.frames.height);
  s.range = colormap_range(s.frames.style, s.tool, s.start_positions, s.duration);
  s.writer = std::make_unique<FrameWriter>(s.outputs, s.outdir, expected_frame_count(s.duration, s.frames.rate),
                                           cv::Size(s.frames.width, s.frames.height));
  const double t = backend.time();
  s.render_frame(model, backend, t, s.tool ? s.tool->position_at(t) : Vec3::Zero(),
                 s.tool ? s.tool->orientation_at(t) : Quat::Identity());
}

void FrameRecorder::on_tick(const Model& model, Backend& backend, const TickInfo& info) {
  Impl& s = *impl_;
  // Frame k is due at k / rate; a tick renders at most one frame (frames
  // faster than ticks are skipped to the next due one).
  const double due = s.next_due / s.frames.rate;
  if (info.t + 1e-9 < due) return;
  s.render_frame(model, backend, info.t, info.tool_center, info.tool_orientation);
}

void FrameRecorder::on_finish(const Model& /*model*/, Backend& /*backend*/) {
  if (impl_->writer) impl_->writer->finish();
}

FrameRecorderTiming FrameRecorder::timing() const {
  FrameRecorderTiming t = impl_->timing;
  if (impl_->writer) t.encode_ms = impl_->writer->timing().encode_ms_total;
  return t;
}

std::unique_ptr<FrameRecorder> make_frame_recorder(const FrameOutputs& outputs, const std::filesystem::path& outdir,
                                                   double duration, std::optional<ToolSpec> tool) {
  if (!outputs.any()) return nullptr;
  return std::make_unique<FrameRecorder>(outputs, outdir, duration, std::move(tool));
}

std::unique_ptr<FrameRecorder> make_frame_recorder(const Scenario& scenario, const std::filesystem::path& outdir) {
  std::optional<ToolSpec> tool;
  if (scenario.tool) tool = scenario.tool->spec;
  return make_frame_recorder(to_frame_outputs(scenario.outputs), outdir, scenario.time.duration, std::move(tool));
}

}  // namespace organsim
