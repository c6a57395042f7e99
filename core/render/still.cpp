#include "core/render/still.h"

#include "core/gl/egl_context.h"
#include "core/mesh/boundary.h"
#include "core/mesh/mesh_io.h"
#include "core/render/surface_renderer.h"
#include "core/util/error.h"

namespace organsim {

StillResult render_still(const TriangleMesh& surface, const StillOptions& options) {
  if (surface.faces.empty()) throw Error(ErrorKind::Input, "nothing to render: the surface has no faces");
  gl::EglContext context;
  SurfaceRenderer renderer(options.width, options.height);
  renderer.set_faces(surface.faces, static_cast<int32_t>(surface.points.size()));
  renderer.set_positions(surface.points);
  const Camera camera =
      make_camera(options.camera, surface.points, static_cast<double>(options.width) / options.height);
  StillResult result;
  result.image = renderer.render(camera, options.style, {});
  result.triangles = surface.faces.size();
  result.renderer = context.renderer();
  return result;
}

StillResult render_mesh_file(const std::filesystem::path& path, const StillOptions& options) {
  TriangleMesh surface;
  if (is_surface_path(path)) {
    surface = read_surface(path);
  } else if (is_tet_mesh_path(path)) {
    TetMesh mesh = read_tet_mesh(path);
    surface.faces = extract_boundary_faces(mesh.tets);
    surface.points = std::move(mesh.points);
  } else {
    throw input_error(path.string(),
                      "unknown mesh extension (expected .off .obj .stl .ply or .mesh .vtk .msh)");
  }
  return render_still(surface, options);
}

}  // namespace organsim
