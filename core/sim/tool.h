#pragma once
// The tool as a backend sees it: its mode, its pose per step, the points a
// pulling tool holds and the reaction it feels. The scripted tool (keyframes,
// grasp and release times) is core/scenario/tool_spec.h.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/util/vec.h"

namespace organsim {

enum class ToolMode { Push, Pull };
// Where a pushing tool's penalty acts: on the boundary surface's triangles
// (at each one's closest point, spread to its corners) or on the points alone.
enum class ToolContact { Surface, Points };
// The tool's shape: a sphere about the frame origin, or a capsule (the
// points within the radius of a segment fixed in the tool's frame).
enum class ToolShape { Sphere, Capsule };

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
  ToolShape shape = ToolShape::Sphere;
  Vec3 end_a{0, 0, 0}, end_b{0, 0, 0};  // capsule: the segment's ends in the tool frame, m
};

// The tool's shape placed in the world for one substep: the segment a-b
// swept by the radius (a == b == origin for a sphere) and the frame origin
// the reaction's torque is taken about.
struct ToolPlacement {
  Vec3 origin{0, 0, 0}, a{0, 0, 0}, b{0, 0, 0};  // m
  double radius = 0;                              // m
  // The radius of a ball about the origin that holds the whole tool (the
  // radius itself for a sphere).
  double reach() const { return radius + std::max((a - origin).norm(), (b - origin).norm()); }
};

// A sphere's segment is its centre exactly; a capsule's ends are rotated
// into the world and moved to the origin.
inline ToolPlacement place_tool(const BackendTool& tool, const Vec3& origin, const Quat& rotation) {
  ToolPlacement p{origin, origin, origin, tool.radius};
  if (tool.shape == ToolShape::Capsule) {
    p.a = origin + rotation * tool.end_a;
    p.b = origin + rotation * tool.end_b;
  }
  return p;
}

// "sphere" or "capsule".
inline const char* shape_name(ToolShape shape) { return shape == ToolShape::Capsule ? "capsule" : "sphere"; }

}  // namespace organsim
