#pragma once
// The tool as a backend sees it: its mode, its pose per step, the points a
// pulling tool holds and the reaction it feels. The scripted tool (keyframes,
// grasp and release times) is core/scenario/tool_spec.h.
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

enum class ToolMode { Push, Pull };
// Where a pushing tool's penalty acts: on the boundary surface's triangles
// (at each one's closest point, spread to its corners) or on the points alone.
enum class ToolContact { Surface, Points };

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
  ToolContact contact = ToolContact::Surface;  // push only
};

}  // namespace organsim
