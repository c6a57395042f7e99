#pragma once
// The per-point gather of ImplicitSystem::apply (implicit_system.h) on
// Google Highway, compiled for the same targets as the CPU kernel
// (cpu_kernel_simd.h) and chosen at run time: one register of points at a
// time, each lane one point, its springs' and tet corners' terms read slot
// by slot in the point's incidence order, the neighbours' values with
// gathers. Each lane adds its terms in the scalar gather's order, so the
// result differs from it by rounding only (fused multiply-adds where the
// target has them), and not with the thread count.
#include <cstdint>
#include <vector>

#include "core/sim/cpu_kernel_simd.h"
#include "core/util/aligned_vector.h"

namespace organsim {

// A group's points are kGatherGroup consecutive ones; a target of fewer
// lanes takes a group in several registers. Its springs are rows of
// kGatherGroup slots (slot l of a row: lane l's next spring), as many rows
// as the group's point with the most; a point's unused slots have zero
// coefficients and itself as the other end. Tet corners alike, unused
// slots naming the zero coefficient at index ntet.
inline constexpr int32_t kGatherGroup = 8;

struct GatherStreams {
  int32_t groups = 0;                           // whole groups: the points past them are gathered by the scalar code
  std::vector<int32_t> spring_row, corner_row;  // first row of each group (groups + 1)
  AlignedVector<int32_t> other3;                // 3 x the spring's other end, per slot
  AlignedVector<double> u[3], axial, transverse, damper;  // the spring's tangent (ImplicitSystem::SpringTangent)
  AlignedVector<int32_t> corner_tet;                      // the corner's tet, per slot
  AlignedVector<double> gradient[3];                      // dV_t/dx_i of the corner
};

// The coefficients of one product: y_i = mass_coef m_i p_i + sum over the
// springs (alpha d + beta axial) (u . dp) u + beta transverse dp (dp = p_i
// - p_other) + sum over the corners tet_coef[t] dV_t/dx_i (when volume).
struct GatherTerms {
  double mass_coef = 0, alpha = 0, beta = 0;
  const double* mass = nullptr;      // npoint
  const double* tet_coef = nullptr;  // ntet + 1, the last 0
  bool volume = false;
};

// out (3 per point, interleaved as p) for the points of groups [first, last).
using GatherGroups = void (*)(const GatherStreams& s, const GatherTerms& terms, const double* p, double* out,
                              int32_t first, int32_t last);

// The gather compiled for `target` (one of simd_targets_supported()).
GatherGroups implicit_gather_for(const SimdTarget& target);

}  // namespace organsim
