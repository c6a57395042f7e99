// organsim render MESH -o IMAGE.png: a still of a surface or tet mesh. This
// file also hands `organsim run` its rendering observers: the frame recorder
// (outputs.frames, video, contact_sheet) and forces.png.
#include <cstdio>
#include <iostream>
#include <sstream>

#include "app/command.h"
#include "app/run_observers.h"
#include "core/render/force_plot_recorder.h"
#include "core/render/frame_recorder.h"
#include "core/render/image_io.h"
#include "core/render/still.h"
#include "core/util/error.h"

namespace organsim::app {
namespace {

// "x,y,z" -> Vec3; `flag` names the option in the error.
Vec3 parse_vec3(const std::string& text, const std::string& flag) {
  Vec3 v;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x() >> c1 >> v.y() >> c2 >> v.z()) || c1 != ',' || c2 != ',' || !(in >> std::ws).eof()) {
    throw Error(ErrorKind::Usage, flag + ": expected three comma-separated numbers like 0.1,0.2,0.3, got \"" + text + "\"");
  }
  return v;
}

struct RenderArgs {
  std::string mesh, output;
  int width = 640, height = 480;
  std::string position, target, up, background;
  double fov = 40.0;
  bool wireframe = false;
};

void run(const RenderArgs& a) {
  StillOptions options;
  options.width = a.width;
  options.height = a.height;
  options.camera.fov_deg = a.fov;
  if (!a.up.empty()) options.camera.up = parse_vec3(a.up, "--camera-up");
  if (!a.position.empty()) {
    options.camera.auto_fit = false;
    options.camera.position = parse_vec3(a.position, "--camera-position");
  }
  options.style.wireframe = a.wireframe;
  if (!a.background.empty()) options.style.background = parse_vec3(a.background, "--background");
  if (!a.target.empty() && a.position.empty()) {
    throw Error(ErrorKind::Usage, "--camera-target needs --camera-position (without both the camera frames the mesh)");
  }
  if (!a.target.empty()) {
    options.camera.target = parse_vec3(a.target, "--camera-target");
  } else {
    options.camera.target_at_center = true;  // an explicit eye looks at the mesh
  }
  const StillResult result = render_mesh_file(a.mesh, options);
  write_image_atomically(a.output, result.image);
  std::cout << "wrote " << a.output << " (" << result.image.cols << "x" << result.image.rows << " px, "
            << result.triangles << " triangles, " << result.renderer << ")\n";
}

const bool render_registered = register_command("render", 60, [](CLI::App& root) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = root.add_subcommand(
      "render",
      "Render a still image of a surface (.off .obj .stl .ply) or tet mesh (.mesh .vtk .msh; its boundary) "
      "off-screen through EGL. Coordinates in m.");
  cmd->add_option("MESH", args->mesh, "mesh file")->required();
  cmd->add_option("-o,--output", args->output, "image file (.png; format by extension)")->required();
  cmd->add_option("--width", args->width, "image width, px (default 640)")->check(CLI::Range(16, 8192));
  cmd->add_option("--height", args->height, "image height, px (default 480)")->check(CLI::Range(16, 8192));
  cmd->add_option("--camera-position", args->position, "eye x,y,z in m (default: auto-fit to the bounding box)");
  cmd->add_option("--camera-target", args->target, "looked-at x,y,z in m (default: bounding box centre)");
  cmd->add_option("--camera-up", args->up, "up direction x,y,z (default 0,0,1)");
  cmd->add_option("--fov", args->fov, "vertical field of view, degrees (default 40)")->check(CLI::Range(1.0, 179.0));
  cmd->add_option("--background", args->background, "background r,g,b in 0..1 (default 1,1,1)");
  cmd->add_flag("--wireframe", args->wireframe, "draw triangle edges over the surface");
  cmd->callback([args] { run(*args); });
});

// `organsim run`: frames/video/contact sheet when outputs.frames is present
// (no renderer and no GL context otherwise), forces.png with the force log.
const bool frames_registered = register_run_observer(
    {"frames", "frames", [](const RunObserverContext& c) -> std::unique_ptr<RunObserver> {
       return make_frame_recorder(c.scenario, c.outdir);
     }});
const bool forces_plot_registered = register_run_observer(
    {"forces.png", "forces_png", [](const RunObserverContext& c) -> std::unique_ptr<RunObserver> {
       if (!c.scenario.outputs.forces) return nullptr;
       return std::make_unique<ForcePlotRecorder>(c.outdir / "forces.png", c.scenario.time.tick(),
                                                  c.scenario.time.ticks());
     }});

}  // namespace
}  // namespace organsim::app
