#pragma once
// The part of model building shared by build_model (a mesh loaded) and
// rebuild_model (a topology change): everything derived from the points'
// rest positions, the tets and their rest volumes. Internal to core/model.
#include <cstdint>
#include <vector>

#include "core/model/model.h"

namespace organsim {

// Fills masses, inverse masses and fixed flags, springs (ends, rest length,
// stiffness, damper), the volume term (per tet or nodal), the boundary
// surface with each point's triangles and the gather layout of `model`, whose rest_position, tet_points, tet_rest_volume,
// sutures, material, gravity and viscous_damping are set (sutures become the
// last springs). `held` (npoint) marks points the scene holds fixed; points
// used by no tet have no mass and are held too.
void assemble_model(Model& model, const std::vector<uint8_t>& held, int32_t chunk_size, int32_t sort_window);

}  // namespace organsim
