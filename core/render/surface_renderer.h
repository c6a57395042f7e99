#pragma once
// Draws a triangle surface (a tet mesh's boundary or a read surface) and the
// tool sphere into an off-screen framebuffer (colour + depth renderbuffers)
// and reads the image back. Needs a current OpenGL 4.5 context (organsim_gl's
// EglContext); every GL object is created and destroyed in that context.
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "core/render/camera.h"
#include "core/render/frame_options.h"

namespace organsim {

// The tool as drawn: the points within `radius` of the segment a-b (a
// sphere when a == b == its centre, else a capsule), and of a2-b2 when
// there are two (a grasper's jaws).
struct ToolDraw {
  bool visible = false;
  Vec3 a{0, 0, 0}, b{0, 0, 0};  // m
  double radius = 0;            // m
  int segments = 1;
  Vec3 a2{0, 0, 0}, b2{0, 0, 0};  // m
};

class SurfaceRenderer {
 public:
  // Size in px. Throws Error(Backend) when a shader does not compile or the
  // framebuffer is incomplete (message names the shader or the status).
  SurfaceRenderer(int width, int height);
  ~SurfaceRenderer();
  SurfaceRenderer(const SurfaceRenderer&) = delete;
  SurfaceRenderer& operator=(const SurfaceRenderer&) = delete;

  int width() const;
  int height() const;

  // Topology: outward triangles over point ids [0, npoint). Builds the index
  // buffer and each point's ring of faces for smooth normals. Call again
  // whenever the topology changes (e.g. after extract_boundary_faces).
  void set_faces(const std::vector<Tri>& faces, int32_t npoint);

  // Positions from the CPU (npoint, m): uploaded as floats to the renderer's
  // own storage buffer.
  void set_positions(const std::vector<Vec3>& positions);
  // Positions straight from an existing GL storage buffer (e.g. the GL
  // backend's x_t): point i at floats [offset + i*stride, +3). The buffer must
  // live in this context (or a shared one) and outlive the draw.
  void use_position_buffer(uint32_t buffer, int stride_floats, int offset_floats);

  // Per-point colours (RGB in [0,1], npoint), or empty for the style's flat colour.
  void set_point_colors(const std::vector<Vec3f>& rgb);
  // Per-face colours (RGB in [0,1], one per face of set_faces, in its order),
  // or empty; they take precedence over point colours. Set again after set_faces.
  void set_face_colors(const std::vector<Vec3f>& rgb);
  // Edges drawn as dark lines over the surface (e.g. where two labels meet:
  // edges_between_face_groups), or empty. Point ids as in set_faces.
  void set_lines(const std::vector<Edge>& edges);

  // Draws into the framebuffer (no read-back); glFinish is not called.
  void draw(const Camera& camera, const StyleOptions& style, const ToolDraw& tool);
  // Reads the framebuffer back as BGR, top row first (OpenCV's order).
  cv::Mat read_back();
  // draw + read_back.
  cv::Mat render(const Camera& camera, const StyleOptions& style, const ToolDraw& tool);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace organsim
