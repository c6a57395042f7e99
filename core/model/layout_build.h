#pragma once
// Builds the per-point gather tables of a Model whose points are already in
// internal order (see layout.h).
#include "core/model/model.h"

namespace organsim {

GatherLayout build_gather_layout(const Model& model, int32_t chunk_size, int32_t sort_window);

}  // namespace organsim
