#pragma once
// What to render and where to write it. The scenario's `outputs` (OutputsDef,
// core/scenario/outputs.h) convert into these with to_frame_outputs();
// `organsim render` fills CameraOptions and StyleOptions from its flags. They
// add what the renderer needs beyond the scenario (colours, tile size).
#include <filesystem>
#include <optional>
#include <string>

#include "core/scenario/outputs.h"
#include "core/util/vec.h"

namespace organsim {

// Look-at camera. `auto_fit` frames the model's rest bounding box (its
// bounding sphere fits the vertical field of view) seen from `auto_direction`.
struct CameraOptions {
  bool auto_fit = true;
  Vec3 position{0, 0, 0};   // eye, m
  Vec3 target{0, 0, 0};     // looked-at point, m
  bool target_at_center = false;  // without auto_fit: look at the bounding box centre instead of target
  Vec3 up{0, 0, 1};         // world up; need not be orthogonal to the view
  double fov_deg = 40.0;    // vertical field of view, degrees (0, 180); the scenario default
  Vec3 auto_direction{1.0, -1.6, 0.9};  // from target towards the eye when auto_fit
};

struct StyleOptions {
  bool wireframe = false;                 // dark edges over the shaded surface
  Colormap colormap = Colormap::None;     // per-vertex colour with a legend
  Vec3 background{1.0, 1.0, 1.0};         // RGB in [0, 1]
  Vec3 surface_color{0.80, 0.45, 0.40};   // RGB in [0, 1], when colormap is None
  Vec3 tool_color{0.55, 0.60, 0.70};      // RGB in [0, 1]
  // Colour map range, fixed for a run; <= 0: estimated before the run from
  // the tool's path (colormap_range.h). Strain is dimensionless (|l/l0 - 1|,
  // mean over a point's springs); displacement is in m, from the run's start.
  double colormap_max = 0.0;
};

struct FramesOptions {
  double rate = 30.0;          // frames per simulated second (1/s)
  int width = 640;             // px
  int height = 480;            // px
  CameraOptions camera;
  StyleOptions style;
  bool write_png = true;       // OUTDIR/frames/frame_00000.png
};

struct VideoOptions {
  std::filesystem::path file = "video.mp4";   // relative to OUTDIR
  std::string codec = "mp4v";  // FOURCC; mp4v and avc1 write .mp4 here
  double fps = 30.0;           // playback frames per second
};

struct ContactSheetOptions {
  std::filesystem::path file = "contact_sheet.png";  // relative to OUTDIR
  int frames = 6;              // tiles, evenly spaced over the run
  int columns = 3;
  int tile_width = 320;        // px; tile height keeps the frame's aspect
};

// Everything the frame recorder writes. No frames, no video and no contact
// sheet => no renderer is created.
struct FrameOutputs {
  std::optional<FramesOptions> frames;  // required by video and contact_sheet
  std::optional<VideoOptions> video;
  std::optional<ContactSheetOptions> contact_sheet;
  bool any() const { return frames.has_value() || video.has_value() || contact_sheet.has_value(); }
};

FrameOutputs to_frame_outputs(const OutputsDef& outputs);
CameraOptions to_camera_options(const CameraDef& camera);

}  // namespace organsim
