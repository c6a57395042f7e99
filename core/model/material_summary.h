#pragma once
// What a Model's materials are, for reports: which labels each material of a
// model with per-label materials is for, and the force log's
// meta.elasticity (`organsim run` writes it; `run --plan` prints the list).
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "core/model/model.h"

namespace organsim {

struct MaterialUse {
  const Material* material = nullptr;  // into the Model
  std::vector<int32_t> labels;         // ascending; empty for the one material of an unlabelled scene
};

// Model::materials in order, each with the tet labels that use it; a model
// with one material gives one entry (Model::material, no labels).
std::vector<MaterialUse> material_uses(const Model& model);

// One material: elasticity_json(model.material) (core/model/stiffness.h).
// Per-label materials: {"per_label": [{"labels": [...], "density": ..., and
// that material's elasticity_json fields}, ...]}.
nlohmann::json model_elasticity_json(const Model& model);

}  // namespace organsim
