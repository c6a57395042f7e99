// Harness for the scenario JSON: parse, then everything `organsim run` does
// before the first step that depends on the scenario alone (the tick count,
// the Model on a small box scaled by mesh.scale, the critical time step and
// its check). The mesh file itself is not read: the mesh readers have their
// own harnesses.
#include <cmath>

#include "core/mesh/tet_mesh.h"
#include "core/scenario/scenario.h"
#include "core/run/run.h"
#include "core/stability/critical_step.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace organsim;
  Scenario s;
  try {
    s = parse_scenario_text(fuzz::as_text(data, size), "/fuzz", fuzz::kSource);
  } catch (const Error& e) {
    fuzz::require_names_file(e);
    return 0;
  }
  fuzz::require(s.time.dt > 0 && s.time.substeps > 0 && s.time.duration > 0, "scenario accepted a non-positive time");
  fuzz::require(s.time.ticks() >= 1, "scenario accepted a run of no ticks");
  fuzz::require(std::isfinite(s.mesh.scale) && s.mesh.scale > 0, "scenario accepted a bad mesh.scale");
  TetMesh mesh = make_box_tet_mesh({0, 0, 0}, {0.1, 0.1, 0.1}, 2, 2, 2);
  for (Vec3& p : mesh.points) p *= s.mesh.scale;
  try {
    const Model model = build_model(mesh, s.material, model_options(s), "box.mesh");
    const ToolSpec* tool = s.tool ? &s.tool->spec : nullptr;
    const StabilityReport report = estimate_critical_step(model, critical_step_options(model, tool));
    check_time_step(report, s.time.dt, s.time.substeps, /*allow_unstable=*/false);
    (void)backend_tool(s);
  } catch (const Error&) {
    // Errors from here on name the JSON path or the mesh; cmd_run adds the file.
  }
  return 0;
}
