#pragma once
// One picture of a surface or a tet mesh's boundary: what `organsim render`
// draws to check a mesh before running it.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

#include "core/mesh/tet_mesh.h"
#include "core/render/frame_options.h"

namespace organsim {

struct StillOptions {
  int width = 640, height = 480;  // px
  CameraOptions camera;           // auto-fit by default
  StyleOptions style;
};

struct StillResult {
  cv::Mat image;            // BGR
  size_t triangles = 0;     // drawn
  std::string renderer;     // GL_RENDERER
};

// Surface as given (faces counter-clockwise seen from outside).
StillResult render_still(const TriangleMesh& surface, const StillOptions& options);
// Reads `path` (.off/.obj/.stl/.ply surface or .mesh/.vtk/.msh tet mesh; a
// tet mesh's boundary is drawn) and renders it. Throws Error(Input) for
// unreadable meshes, Error(Backend) when no GL context can be made.
StillResult render_mesh_file(const std::filesystem::path& path, const StillOptions& options);

}  // namespace organsim
