#pragma once
// The tool as a backend sees it: its mode, its pose per step, the points a
// pulling tool holds and the reaction it feels. The scripted tool (keyframes,
// grasp and release times) is core/scenario/tool_spec.h.
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

enum class ToolMode { Push, Pull };

// Tool state given to a backend for one step.
struct ToolPose {
  Vec3 center{0, 0, 0};  // m
};

// Points grasped by a pulling tool: each follows center + offset through an
// attachment spring of stiffness contact_stiffness.
struct Attachment {
  std::vector<int32_t> points;  // internal ids (nattached)
  std::vector<Vec3> offsets;    // x_i - center at grasp time, m (nattached)
};

// Reaction on the tool: F = -sum f_i, T = sum (x_i - c) x (-f_i).
struct Reaction {
  Vec3 force{0, 0, 0};   // N
  Vec3 torque{0, 0, 0};  // N m, about the tool centre
  int32_t contacts = 0;  // points in contact or attached
};

// The tool parameters a backend needs besides its per-tick pose.
struct BackendTool {
  bool present = false;
  ToolMode mode = ToolMode::Push;
  double radius = 0;             // m
  double contact_stiffness = 0;  // N/m
};

}  // namespace organsim
