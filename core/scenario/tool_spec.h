#pragma once
// The scripted virtual tool as a scenario describes it: a sphere whose centre
// follows keyframes (time, position), linearly interpolated and held constant
// outside them. What a backend needs of it per step is in core/sim/tool.h.
#include <optional>
#include <vector>

#include "core/sim/tool.h"
#include "core/util/vec.h"

namespace organsim {

struct Keyframe {
  double t = 0;            // s
  Vec3 position{0, 0, 0};  // tool centre, m
};

struct ToolSpec {
  double radius = 0.01;                 // sphere radius, m
  double contact_stiffness = 200.0;     // push: penalty N/m per m of penetration; pull: attachment springs N/m
  ToolMode mode = ToolMode::Push;
  ToolContact contact = ToolContact::Surface;  // push: penalty on the surface triangles or on the points
  double grasp_radius = 0.015;          // pull: points within this distance of the centre are grasped, m
  double grasp_time = 0;                // pull: s
  std::optional<double> release_time;   // pull: s; held to the end when absent
  std::vector<Keyframe> keyframes;      // sorted by t, at least one

  Vec3 position_at(double t) const;
};

}  // namespace organsim
