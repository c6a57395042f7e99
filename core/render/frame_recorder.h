#pragma once
// The frame recorder: a RunObserver that renders the model's boundary and the
// tool at `frames.rate` frames per simulated second and hands the images to a
// FrameWriter (PNG sequence, video, contact sheet). It owns its own headless
// EGL context; when another context is current on the thread (the GL
// backend's), it makes its own current for each frame and restores the other
// one afterwards. The EGL context is created in on_start, not before.
#include <filesystem>
#include <memory>
#include <optional>

#include "core/render/frame_options.h"
#include "core/scenario/scenario.h"
#include "core/sim/run_observer.h"
#include "core/scenario/tool_spec.h"

namespace organsim {

struct FrameRecorderTiming {
  int frames = 0;
  double render_ms = 0;    // draw + glFinish, total over frames (run thread)
  double readback_ms = 0;  // glReadPixels + flip + colour map upload, total (run thread)
  double encode_ms = 0;    // PNG/video/tile, total (writer thread)
};

class FrameRecorder : public RunObserver {
 public:
  // tool: drawn as its shape (sphere, capsule or a grasper's jaws) at the tick's pose; nullopt
  // for scenes without a tool. duration (s) sizes the contact sheet.
  FrameRecorder(const FrameOutputs& outputs, const std::filesystem::path& outdir, double duration,
                std::optional<ToolSpec> tool);
  ~FrameRecorder() override;

  void on_start(const Model& model, Backend& backend) override;
  void on_tick(const Model& model, Backend& backend, const TickInfo& info) override;
  void on_finish(const Model& model, Backend& backend) override;
  // Re-extracts the boundary, which now includes the faces a cut opened.
  void on_topology_changed(const Model& next, Backend& backend) override;

  // Recomputes the boundary surface from model.tet_points; call after the
  // topology changed (cuts, removed tets).
  void topology_changed(const Model& model);

  FrameRecorderTiming timing() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// nullptr when `outputs` asks for nothing (no renderer, no GL context).
std::unique_ptr<FrameRecorder> make_frame_recorder(const FrameOutputs& outputs, const std::filesystem::path& outdir,
                                                   double duration, std::optional<ToolSpec> tool);
// The same from a parsed scenario: outputs, time.duration and tool.
std::unique_ptr<FrameRecorder> make_frame_recorder(const Scenario& scenario, const std::filesystem::path& outdir);

}  // namespace organsim
