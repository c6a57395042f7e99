#pragma once
// The scripted virtual tool as a scenario describes it: a shape (sphere,
// capsule or grasper) in the tool's own frame, whose origin follows keyframes (time,
// position), linearly interpolated, and whose orientation is interpolated
// along the shortest arc (slerp), and a grasper's jaw gap linearly; all held
// constant outside the keyframes.
// What a backend needs of it per step is in core/sim/tool.h.
#include <algorithm>
#include <optional>
#include <vector>

#include "core/sim/tool.h"
#include "core/util/vec.h"

namespace organsim {

struct Keyframe {
  double t = 0;            // s
  Vec3 position{0, 0, 0};  // the tool frame's origin (a sphere's centre), m
  Quat orientation = Quat::Identity();  // the tool frame's rotation into the world
  double gap = 0;          // grasper: the distance between its jaws' axes, m
};

struct ToolSpec {
  ToolShape shape = ToolShape::Sphere;
  double radius = 0.01;                 // sphere or capsule radius, m
  Vec3 end_a{0, 0, 0}, end_b{0, 0, 0};  // capsule, grasper: its segment's ends in the tool frame, m
  Friction friction{};                  // surface contact: Coulomb friction, off by default
  bool hertz_layer = false;             // a sphere's or capsule's surface contact: in series with the sub-cell layer
  double contact_stiffness = 200.0;     // push: penalty N/m per m of penetration; pull: attachment springs N/m
  ToolMode mode = ToolMode::Push;
  ToolContact contact = ToolContact::Surface;  // push: penalty on the surface triangles or on the points
  double grasp_radius = 0.015;          // pull: points within this distance of the centre are grasped, m
  double grasp_time = 0;                // pull: s
  std::optional<double> release_time;   // pull: s; held to the end when absent
  std::vector<Keyframe> keyframes;      // sorted by t, at least one

  // The distance from the frame's origin to the farthest end of the
  // capsule's segment (0 for a sphere): the tool lies within radius + this
  // of the origin in any orientation.
  // A grasper's jaws lie up to half their widest gap further out.
  double extent() const;

  // What a backend needs of this tool besides its per-tick pose.
  BackendTool backend_tool() const;

  Vec3 position_at(double t) const;
  // Slerp between the keyframes around t, exactly a keyframe's at its time.
  Quat orientation_at(double t) const;
  // A grasper's jaw gap, linear between the keyframes, m.
  double gap_at(double t) const;
};

}  // namespace organsim
