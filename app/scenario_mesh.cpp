#include "app/scenario_mesh.h"

#include <chrono>
#include <functional>
#include <string>

#include "app/progress_line.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/units.h"
#include "core/run/run.h"
#include "meshing/mesh_image.h"

namespace organsim::app {

namespace {

// Shows the mesher's stage on `line` ("organsim: meshing liver.off: ...").
std::function<void(const std::string&)> meshing_stage_line(ProgressLine& line, const MeshDef& def) {
  return [&line, &def](const std::string& stage) {
    line.show("organsim: meshing " + def.path.filename().string() + ": " + stage);
  };
}

}  // namespace

TetMesh load_scenario_mesh(const MeshDef& def, MeshReport* report) {
  const auto start = std::chrono::steady_clock::now();
  TetMesh mesh;
  if (def.kind == MeshDef::Kind::Surface) {
    // Scale first so that cell_size and facet_distance are in metres of the
    // scaled surface, like every other length in the scenario.
    TriangleMesh surface = read_surface(def.path);
    scale_points(surface.points, def.scale);
    MeshOptions options;
    options.target_points = def.target_points;
    options.cell_size = def.cell_size;
    options.facet_distance = def.facet_distance;
    options.exude = def.exude;
    ProgressLine line;  // meshing a large target takes minutes: say which stage it is in
    options.on_stage = meshing_stage_line(line, def);
    mesh = mesh_surface(surface, options, def.path.string(), report);
  } else if (def.kind == MeshDef::Kind::Image) {
    ImageMeshOptions options;
    options.target_points = def.target_points;
    options.cell_size = def.cell_size;
    options.label_cell_size = def.label_cell_size;
    options.facet_distance = def.facet_distance;
    options.exude = def.exude;
    options.labels = def.labels;
    if (def.scale_given) options.metres_per_unit = def.scale;  // only for a header without a unit
    ProgressLine line;
    options.on_stage = meshing_stage_line(line, def);
    mesh = mesh_image_file(def.path, options, report);
  } else {
    mesh = read_tet_mesh(def.path);
    scale_points(mesh.points, def.scale);
    if (report) *report = describe_tet_mesh(mesh);
  }
  if (report) {
    report->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return mesh;
}

}  // namespace organsim::app
