#pragma once
// What the CPU backend hands its simd kernel (every target, float and double)
// for one substep, and what each chunk hands back.
#include <cstdint>

#include "core/physics/force_law.h"
#include "core/sim/step_plan.h"
#include "core/util/vec.h"

namespace organsim {

// Step-invariant inputs of one substep, in the kernel's precision.
template <class Real>
struct KernelStepInputs {
  Real dt = 0, dt2 = 0, inv_dt = 0, drag = 1;  // dt, dt^2, 1/dt, 1 - alpha dt
  Real shear_damping = 0;                      // tau / dt: the shear element's damper on the increments d = dt v
  Real gravity[3] = {0, 0, 0};
  Real tool_center[3] = {0, 0, 0};           // the tool frame's origin: the torque's reference point
  Real tool_a[3] = {0, 0, 0}, tool_b[3] = {0, 0, 0};  // the shape's segment (a == b == centre: a sphere)
  Real tool_radius = 0, tool_k = 0;
  Real tool_reach = 0;  // a ball about the centre holding the whole tool (the simd kernel's point filter)
  ToolTerm tool = ToolTerm::None;       // this substep's tool pass (none while the tool is inactive)
  const int32_t* attached = nullptr;    // pull: attachment index per point or -1
  const Real* attach_offset = nullptr;  // pull: 3 per attachment
  const Real* tool_scale = nullptr;     // tool stiffness multiplier per point, Model::tool_k_scale
  // Surface contact: the surface-contact pass's force per point (3 per
  // touched point) and each point's index into it or -1 (padding included).
  const int32_t* contact_slot = nullptr;
  const Real* contact_force = nullptr;
};

// Per point, >= 0 for the lanes the tool pass may touch: the attachment
// index (pull) or the surface contact's slot (surface). The simd kernel
// finds its tool lanes with one compare on it.
template <ToolTerm Tool, class Real>
const int32_t* tool_lane_flags(const KernelStepInputs<Real>& in) {
  static_assert(Tool == ToolTerm::Pull || Tool == ToolTerm::Surface);
  return Tool == ToolTerm::Pull ? in.attached : in.contact_slot;
}

// Tool reaction of one chunk (summed by the caller in chunk order, so the
// total is the same for any thread count).
struct ChunkReaction {
  Vec3 force{0, 0, 0}, torque{0, 0, 0};
  int32_t contacts = 0;
};

// The tool's force on point p at x (force_law::push_penalty from the
// shape's segment, or
// pull_attachment, or the surface contact's force on p from its triangles'
// force_law::sphere_triangle_penalty), added to f and (negated) to the
// chunk's reaction; false when p does not touch the tool. One lane at a time: few points touch the
// tool, and the kernels call this only for lanes that may.
template <class Real, ToolTerm Tool>
bool add_tool_force(const KernelStepInputs<Real>& in, int32_t p, const Real x[3], Real f[3], ChunkReaction& partial) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const V3 xl(x[0], x[1], x[2]), ctr(in.tool_center[0], in.tool_center[1], in.tool_center[2]);
  const Real k = in.tool_k * in.tool_scale[p];
  V3 fc;
  if constexpr (Tool == ToolTerm::Push) {
    const V3 a(in.tool_a[0], in.tool_a[1], in.tool_a[2]), b(in.tool_b[0], in.tool_b[1], in.tool_b[2]);
    if (!force_law::push_penalty(V3(xl - force_law::segment_closest_point(xl, a, b)), in.tool_radius, k, fc))
      return false;
  } else if constexpr (Tool == ToolTerm::Surface) {
    const int32_t slot = in.contact_slot[p];
    if (slot < 0) return false;
    const Real* fs = in.contact_force + 3 * slot;
    fc = V3(fs[0], fs[1], fs[2]);
  } else {
    static_assert(Tool == ToolTerm::Pull);
    const int32_t a = in.attached[p];
    if (a < 0) return false;
    const Real* off = in.attach_offset + 3 * a;
    fc = force_law::pull_attachment(V3(ctr + V3(off[0], off[1], off[2])), xl, k);
  }
  for (int j = 0; j < 3; ++j) f[j] += fc[j];
  const Vec3 fd = fc.template cast<double>();
  partial.force -= fd;
  partial.torque += (xl.template cast<double>() - ctr.template cast<double>()).cross(-fd);
  ++partial.contacts;
  return true;
}

}  // namespace organsim
