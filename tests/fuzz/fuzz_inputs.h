#pragma once
// What each kind of harness does with one input, read as the file `source`:
// the harnesses (fuzz_<kind>.cpp) call these, and so does the seed test
// (tests/meshing/fuzz_seeds_test.cpp), which runs every seed of the corpus
// through them. Each either accepts the input (and then checks what the next
// stage relies on, stopping with fuzz::broken when that does not hold, and
// returns what it read) or throws the organsim::Error that refuses it.
#include <cmath>
#include <sstream>
#include <string>
#include <string_view>

#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_detail.h"
#include "core/mesh/mesh_stats.h"
#include "core/mesh/tet_mesh.h"
#include "core/scenario/scenario.h"
#include "core/run/run.h"
#include "core/stability/critical_step.h"
#include "meshing/surface_check.h"
#include "tests/fuzz/fuzz_check.h"

namespace organsim::fuzz {

// kind surface: parse_surface; an accepted surface is valid and survives an
// OFF round trip unchanged (the writers print the shortest exact text).
inline TriangleMesh surface_input(std::string_view text, const std::string& source) {
  TriangleMesh mesh = parse_surface(text, source);
  require_valid_surface(mesh);
  std::ostringstream off;
  mesh_io::write_off(off, mesh);
  const TriangleMesh again = parse_surface(off.str(), "again.off");
  require(again.points == mesh.points && again.faces == mesh.faces, "OFF round trip changed the surface");
  return mesh;
}

inline void require_tet_round_trip(const TetMesh& mesh, const char* name,
                                   void (*write)(std::ostream&, const TetMesh&)) {
  std::ostringstream out;
  write(out, mesh);
  const TetMesh again = parse_tet_mesh(out.str(), name);
  require(again.points == mesh.points && again.tets == mesh.tets,
          std::string("round trip through ") + name + " changed the mesh");
}

// kind tet: parse_tet_mesh (read, orient, validate); an accepted mesh is
// valid and survives medit and VTK round trips unchanged.
inline TetMesh tet_input(std::string_view text, const std::string& source) {
  TetMesh mesh = parse_tet_mesh(text, source);
  require_valid_tet_mesh(mesh);
  require_tet_round_trip(mesh, "again.mesh", mesh_io::write_medit);
  require_tet_round_trip(mesh, "again.vtk", mesh_io::write_vtk);
  return mesh;
}

// kind scenario, first stage: the JSON parse. An accepted scenario has a
// positive time, at least one tick and a usable mesh.scale.
inline Scenario scenario_input(std::string_view text, const std::string& source) {
  Scenario s = parse_scenario_text(text, "/fuzz", source);
  require(s.time.dt > 0 && s.time.substeps > 0 && s.time.duration > 0, "scenario accepted a non-positive time");
  require(s.time.ticks() >= 1, "scenario accepted a run of no ticks");
  require(std::isfinite(s.mesh.scale) && s.mesh.scale > 0, "scenario accepted a bad mesh.scale");
  return s;
}

// kind scenario, second stage: what `organsim run` does before the first
// step that depends on the scenario alone (the Model on a small box scaled
// by mesh.scale, the critical time step and its check, the backend's tool).
// The mesh file itself is not read: the mesh readers have their own
// harnesses. Its errors name the JSON path or the mesh (cmd_run adds the file).
inline void scenario_model(const Scenario& s) {
  TetMesh mesh = make_box_tet_mesh({0, 0, 0}, {0.1, 0.1, 0.1}, 2, 2, 2);
  for (Vec3& p : mesh.points) p *= s.mesh.scale;
  const Model model = build_model(mesh, s.material, model_options(s), "box.mesh");
  const ToolSpec* tool = s.tool ? &s.tool->spec : nullptr;
  const StabilityReport report = estimate_critical_step(model, critical_step_options(model, tool));
  check_time_step(report, s.time.dt, s.time.substeps, /*allow_unstable=*/false);
  (void)backend_tool(s);
}

// kind surface_check: the checks that guard CGAL Mesh_3 (meshing/
// surface_check.h); a surface that passes is valid, closed (at least 4
// faces) and encloses a positive volume.
inline TriangleMesh surface_check_input(std::string_view text, const std::string& source) {
  const TriangleMesh surface = parse_surface(text, source);
  std::vector<std::string> notes;
  const TriangleMesh checked = check_surface(surface, source, notes);
  require_valid_surface(checked);
  require(checked.faces.size() >= 4, "a closed surface with fewer than 4 faces passed");
  require(surface_volume(checked) > 0, "a surface enclosing no positive volume passed");
  return checked;
}

}  // namespace organsim::fuzz
