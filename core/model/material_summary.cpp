#include "core/model/material_summary.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "core/model/stiffness.h"

namespace organsim {

std::vector<MaterialUse> material_uses(const Model& model) {
  if (model.materials.empty()) return {MaterialUse{&model.material, {}}};
  std::vector<MaterialUse> uses(model.materials.size());
  for (size_t m = 0; m < uses.size(); ++m) uses[m].material = &model.materials[m];
  for (size_t t = 0; t < model.tet_material.size(); ++t) {
    if (!model.tet_label.empty()) uses[model.tet_material[t]].labels.push_back(model.tet_label[t]);
  }
  for (MaterialUse& u : uses) {
    std::sort(u.labels.begin(), u.labels.end());
    u.labels.erase(std::unique(u.labels.begin(), u.labels.end()), u.labels.end());
  }
  return uses;
}

nlohmann::json model_elasticity_json(const Model& model) {
  if (model.materials.empty()) return elasticity_json(model.material);
  nlohmann::json per_label = nlohmann::json::array();
  for (const MaterialUse& u : material_uses(model)) {
    nlohmann::json j = elasticity_json(*u.material);
    j["labels"] = u.labels;
    j["density"] = u.material->density;
    per_label.push_back(std::move(j));
  }
  return {{"per_label", per_label}};
}

}  // namespace organsim
