#pragma once
// What `--plan` adds to a backend's surface-contact pass for the sub-cell
// Hertz layer and friction (the same words on every backend).
#include <string>

#include "core/sim/tool.h"

namespace organsim {

// "" without the layer.
inline std::string hertz_layer_plan(const BackendTool& tool) {
  if (!tool.hertz_layer) return "";
  return std::string(", then every penalty lowered as by the ") + shape_name(tool.shape) +
         " moved back through the sub-cell layer (" +
         (tool.shape == ToolShape::Sphere ? "Hertz's" : "Hertz's at its ends, the line's along its shaft") +
         " law; one root per substep, force_law::HertzLayer)";
}

// "" without friction.
inline std::string friction_plan(const BackendTool& tool) {
  if (!tool.friction.on()) return "";
  return ", then Coulomb friction per touched point (stick anchor in the tool frame, mu_s " +
         std::to_string(tool.friction.mu_s) + ", mu_k " + std::to_string(tool.friction.mu_k) + ")";
}

}  // namespace organsim
