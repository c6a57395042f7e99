#pragma once
// The scripted virtual tool: a sphere whose centre follows keyframes
// (time, position), linearly interpolated and held constant outside them.
#include <optional>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

enum class ToolMode { Push, Pull };

struct Keyframe {
  double t = 0;            // s
  Vec3 position{0, 0, 0};  // tool centre, m
};

struct ToolSpec {
  double radius = 0.01;                 // sphere radius, m
  double contact_stiffness = 200.0;     // push: penalty N/m per m of penetration; pull: attachment springs N/m
  ToolMode mode = ToolMode::Push;
  double grasp_radius = 0.015;          // pull: points within this distance of the centre are grasped, m
  double grasp_time = 0;                // pull: s
  std::optional<double> release_time;   // pull: s; held to the end when absent
  std::vector<Keyframe> keyframes;      // sorted by t, at least one

  Vec3 position_at(double t) const;
};

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

}  // namespace organsim
