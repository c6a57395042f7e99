#pragma once
// Loads a scenario's mesh: reads a tet mesh, or reads a surface or a
// labelled image and meshes it with CGAL (meshing/), applying the scenario's
// scale. In app/ because core/ must not depend on meshing/ (CGAL).
#include "core/mesh/tet_mesh.h"
#include "core/model/model.h"
#include "core/scenario/scenario.h"
#include "meshing/mesh_surface.h"

namespace organsim::app {

// `report` (optional) receives counts and quality; its `seconds` is the time
// taken to read and (for surfaces) mesh.
TetMesh load_scenario_mesh(const MeshDef& mesh, MeshReport* report = nullptr);

}  // namespace organsim::app
