#include "core/render/frame_options.h"

#include <algorithm>

namespace organsim {

CameraOptions to_camera_options(const CameraDef& camera) {
  CameraOptions c;
  c.auto_fit = camera.auto_fit;
  c.position = camera.position;
  c.target = camera.target;
  c.up = camera.up;
  c.fov_deg = camera.fov_deg;
  return c;
}

FrameOutputs to_frame_outputs(const OutputsDef& outputs) {
  FrameOutputs out;
  if (!outputs.frames) return out;  // video and contact sheet need frames
  const FramesDef& f = *outputs.frames;
  FramesOptions frames;
  frames.rate = f.rate;
  frames.width = f.size[0];
  frames.height = f.size[1];
  frames.camera = to_camera_options(f.camera);
  frames.style.wireframe = f.style.wireframe;
  frames.style.colormap = f.style.colormap;
  frames.style.colormap_max = f.style.colormap_max;
  frames.style.background = Vec3(f.style.background[0], f.style.background[1], f.style.background[2]);
  out.frames = frames;
  if (outputs.video) {
    VideoOptions v;
    v.file = outputs.video->file;
    v.codec = outputs.video->codec;
    v.fps = outputs.video->fps;
    out.video = v;
  }
  if (outputs.contact_sheet) {
    ContactSheetOptions c;
    c.frames = outputs.contact_sheet->frames;
    c.columns = outputs.contact_sheet->columns;
    // Tiles no wider than the frames (a sheet never upsamples).
    c.tile_width = std::min(c.tile_width, frames.width);
    out.contact_sheet = c;
  }
  return out;
}

}  // namespace organsim
