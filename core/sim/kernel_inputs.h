#pragma once
// What the CPU backend hands the AVX-512 kernels (float and double) for one
// substep, and what each chunk hands back.
#include <cstdint>

#include "core/util/vec.h"

namespace organsim {

// Step-invariant inputs of one substep, in the kernel's precision.
template <class Real>
struct KernelStepInputs {
  Real dt2 = 0, inv_dt = 0, drag = 1;  // dt^2, 1/dt, 1 - alpha dt
  Real gravity[3] = {0, 0, 0};
  Real tool_center[3] = {0, 0, 0};
  Real tool_radius = 0, tool_k = 0;
  enum Tool { None, Push, Pull } tool = None;
  const int32_t* attached = nullptr;    // pull: attachment index per point or -1 (npad)
  const Real* attach_offset = nullptr;  // pull: 3 per attachment
  const Real* tool_scale = nullptr;     // tool stiffness multiplier per point, Model::tool_k_scale (npad)
};

// Tool reaction of one chunk (summed by the caller in chunk order, so the
// total is the same for any thread count).
struct ChunkReaction {
  Vec3 force{0, 0, 0}, torque{0, 0, 0};
  int32_t contacts = 0;
};

// The tool's force on point p at x, added to f and (negated) to the chunk's
// reaction; false when p does not touch the tool. One lane at a time: few
// points touch the tool, and the kernels call this only for lanes that may.
template <class Real, bool Push>
bool add_tool_force(const KernelStepInputs<Real>& in, int32_t p, const Real x[3], Real f[3], ChunkReaction& partial) {
  using V3 = Eigen::Matrix<Real, 3, 1>;
  const V3 xl(x[0], x[1], x[2]), ctr(in.tool_center[0], in.tool_center[1], in.tool_center[2]);
  V3 fc;
  if constexpr (Push) {
    const V3 o = xl - ctr;
    const Real dist = o.norm();
    if (dist >= in.tool_radius) return false;
    const V3 n = dist > 0 ? V3(o / dist) : V3(0, 0, 1);
    fc = in.tool_k * in.tool_scale[p] * (in.tool_radius - dist) * n;
  } else {
    const Real* off = in.attach_offset + 3 * in.attached[p];
    fc = in.tool_k * in.tool_scale[p] * (ctr + V3(off[0], off[1], off[2]) - xl);
  }
  for (int k = 0; k < 3; ++k) f[k] += fc[k];
  const Vec3 fd = fc.template cast<double>();
  partial.force -= fd;
  partial.torque += (xl.template cast<double>() - ctr.template cast<double>()).cross(-fd);
  ++partial.contacts;
  return true;
}

}  // namespace organsim
