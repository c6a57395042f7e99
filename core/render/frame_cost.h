#pragma once
// What one frame costs, for `organsim bench`: the model's boundary rendered
// at the given size with the recorder's own code paths, timed per stage.
#include <string>

#include "core/model/model.h"

namespace organsim {

struct FrameCost {
  int frames = 0;                 // measured (after one warm-up frame)
  int width = 0, height = 0;      // px
  size_t triangles = 0;           // boundary triangles drawn
  std::string renderer;           // GL_RENDERER
  // Medians, ms per frame.
  double upload_ms = 0;           // positions -> storage buffer (CPU backend path)
  double render_ms = 0;           // draw + glFinish
  double readback_ms = 0;         // glReadPixels + vertical flip
  double png_ms = 0;              // PNG encoding (writer thread in a run)
  double video_ms = 0;            // mp4v encoding of one frame (writer thread in a run)
  // What the run loop itself pays per frame: upload + render + read-back.
  double run_loop_ms() const { return upload_ms + render_ms + readback_ms; }
};

// Creates its own EGL context. Throws Error(Backend) when none can be made.
FrameCost measure_frame_cost(const Model& model, int width = 640, int height = 480, int frames = 20);

}  // namespace organsim
