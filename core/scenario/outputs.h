#pragma once
// The scenario's `outputs` section: what a run writes besides its force log.
// Parsed and validated in full by parse_scenario() so that the frame recorder
// (render/) only consumes these structs. Sizes in pixels, rates per simulated
// second, colours as [r, g, b] in 0..1. Documented in docs/scenarios.md.
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "core/util/vec.h"

namespace organsim {

// Camera looking from `position` at `target`; auto_fit frames the model's
// rest bounding box instead (the other fields are then unused).
struct CameraDef {
  bool auto_fit = true;
  Vec3 position{0, 0, 0};  // m
  Vec3 target{0, 0, 0};    // m
  Vec3 up{0, 0, 1};
  double fov_deg = 40.0;   // vertical field of view, degrees, in (0, 180)
};

enum class Colormap { None, Strain, Displacement, Label };

struct FrameStyle {
  bool wireframe = false;                 // edges drawn over the shaded surface
  Colormap colormap = Colormap::None;     // spring strain, point displacement (with a scale) or tet label (with a key)
  std::array<double, 3> background{1.0, 1.0, 1.0};  // r, g, b in 0..1
  // Top of the colour scale, kept for the whole run (m for displacement,
  // dimensionless for strain); 0: estimated before the run from the tool's path.
  double colormap_max = 0;
};

// OUTDIR/frames/frame_00000.png ...
struct FramesDef {
  double rate = 30.0;                     // frames per simulated second, > 0
  std::array<int32_t, 2> size{640, 480};  // width, height in pixels, each in 16..8192
  CameraDef camera;
  FrameStyle style;
};

// OUTDIR/<file>: the frames as a video (needs `frames`).
struct VideoDef {
  std::string file = "video.mp4";  // relative to OUTDIR
  std::string codec = "mp4v";      // FourCC, 4 characters
  double fps = 30.0;               // playback frames per second; defaults to frames.rate
};

// OUTDIR/contact_sheet.png: N evenly spaced frames in a grid (needs `frames`).
struct ContactSheetDef {
  int32_t frames = 6;   // images on the sheet, >= 1
  int32_t columns = 3;  // grid columns, >= 1
};

// OUTDIR/vtk/state_00000.vtu ... and OUTDIR/states.pvd: the model's state as a
// ParaView time series (docs/scenarios.md lists the arrays).
struct VtkSeriesDef {
  double rate = 30.0;         // states per simulated second, > 0
  bool surface_only = false;  // boundary triangles as .vtp (smaller, for long runs) instead of the tets
};

struct OutputsDef {
  bool forces = true;  // OUTDIR/forces.json
  std::optional<VtkSeriesDef> vtk;
  std::optional<FramesDef> frames;
  std::optional<VideoDef> video;
  std::optional<ContactSheetDef> contact_sheet;

  bool wants_rendering() const { return frames.has_value(); }
};

const char* colormap_name(Colormap c);

}  // namespace organsim
