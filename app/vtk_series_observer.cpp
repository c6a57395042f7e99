// `organsim run`: the ParaView series (OUTDIR/vtk/, OUTDIR/states.pvd) when
// the scenario has outputs.vtk.
#include "app/run_observers.h"
#include "core/io/vtk_series.h"

namespace organsim::app {
namespace {

const bool vtk_series_registered = register_run_observer(
    {"states.pvd", "vtk", [](const RunObserverContext& c) -> std::unique_ptr<RunObserver> {
       if (!c.scenario.outputs.vtk) return nullptr;
       std::optional<ToolSpec> tool;
       if (c.scenario.tool) tool = c.scenario.tool->spec;
       return std::make_unique<VtkSeriesRecorder>(*c.scenario.outputs.vtk, c.outdir, c.scenario.time.tick(), tool);
     }});

}  // namespace
}  // namespace organsim::app
