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
// The tool's shape: a sphere about the frame origin, a capsule (the points
// within the radius of a segment fixed in the tool's frame), or a grasper:
// two capsule jaws parallel to that segment, `gap` apart along the tool
// frame's y axis (kJawAxis), closing and opening as its keyframes say.
enum class ToolShape { Sphere, Capsule, Grasper };
inline const Vec3 kJawAxis{0, 1, 0};

// Coulomb friction between the tool and the tissue
// (force_law::anchor_friction): static and kinetic coefficients, off when
// mu_s is 0.
struct Friction {
  double mu_s = 0, mu_k = 0;
  bool on() const { return mu_s > 0; }
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
  double grip = 0;       // a grasper: its jaws' penalties along their closing directions, summed, N
};

// The tool parameters a backend needs besides its per-tick pose.
struct BackendTool {
  bool present = false;
  ToolMode mode = ToolMode::Push;
  double radius = 0;             // m
  double contact_stiffness = 0;  // N/m
  ToolContact contact = ToolContact::Surface;  // push only
  ToolShape shape = ToolShape::Sphere;
  Vec3 end_a{0, 0, 0}, end_b{0, 0, 0};  // capsule, grasper: the segment's ends in the tool frame, m
  Friction friction{};                  // surface contact only
  // A sphere's or capsule's surface contact in series with the sub-cell
  // layer (force_law::HertzLayer): Hertz's force, or a line load's along a
  // capsule's shaft, where the contact is narrower than the cells.
  bool hertz_layer = false;
  int32_t jaws() const { return shape == ToolShape::Grasper ? 2 : 1; }
  // The contact stiffness a point can feel, as a multiple of its penalty
  // share k s_i: up to k s_i from each jaw's normal penalty, and with
  // friction k s_i from the stick spring plus up to 2 mu_s k s_i from the
  // friction limit's slope (mu N, N's gradient at most k s_i, and the
  // normal's turning). What dt_crit counts (critical_step.h).
  double stiffness_factor() const { return jaws() + (friction.on() ? 1 + 2 * friction.mu_s : 0.0); }
};

// The tool's shape placed in the world for one substep: the segment a-b
// swept by the radius (a == b == origin for a sphere; a grasper's first
// jaw, its second a2-b2), the frame origin the reaction's torque is taken
// about, and the frame's rotation (friction keeps its anchors in the frame).
struct ToolPlacement {
  Vec3 origin{0, 0, 0}, a{0, 0, 0}, b{0, 0, 0};  // m
  double radius = 0;                              // m
  Vec3 a2{0, 0, 0}, b2{0, 0, 0};                  // grasper: the second jaw, m
  int32_t jaws = 1;
  Quat rotation = Quat::Identity();
  // The radius of a ball about the origin that holds the whole tool (the
  // radius itself for a sphere).
  double reach() const {
    double far = std::max((a - origin).norm(), (b - origin).norm());
    if (jaws == 2) far = std::max({far, (a2 - origin).norm(), (b2 - origin).norm()});
    return radius + far;
  }
};

// A sphere's segment is its centre exactly; a capsule's ends are rotated
// into the world and moved to the origin; a grasper's jaws are its segment
// moved by +-gap/2 along the frame's jaw axis.
inline ToolPlacement place_tool(const BackendTool& tool, const Vec3& origin, const Quat& rotation, double gap = 0) {
  ToolPlacement p;
  p.origin = p.a = p.b = p.a2 = p.b2 = origin;
  p.radius = tool.radius;
  p.rotation = rotation;
  if (tool.shape == ToolShape::Sphere) return p;
  p.a = origin + rotation * tool.end_a;
  p.b = origin + rotation * tool.end_b;
  if (tool.shape == ToolShape::Grasper) {
    const Vec3 half = rotation * (gap / 2 * kJawAxis);
    p.jaws = 2;
    p.a2 = p.a - half, p.b2 = p.b - half;
    p.a += half, p.b += half;
  }
  return p;
}

// "sphere", "capsule" or "grasper".
inline const char* shape_name(ToolShape shape) {
  return shape == ToolShape::Capsule ? "capsule" : shape == ToolShape::Grasper ? "grasper" : "sphere";
}

}  // namespace organsim
