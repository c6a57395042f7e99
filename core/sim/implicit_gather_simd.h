#pragma once
// The passes of ImplicitSystem::apply (implicit_system.h) on Google
// Highway, compiled for the same targets as the CPU kernel
// (cpu_kernel_simd.h) and chosen at run time. The per-point gather takes
// one register of points at a time, each lane one point, its springs' and
// tet corners' terms read slot by slot in the point's incidence order, the
// neighbours' values with gathers; the volume term's per-tet and per-node
// scalars a register of tets or points at a time. Each lane adds its terms
// in the scalar code's order, so the result differs from it by rounding
// only (fused multiply-adds where the target has them), and not with the
// thread count.
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
  // The volume term's tets, kGatherGroup to a group, as many whole groups
  // as they fill (the rest in scalar code): corner c's point and dV_t/dx_c.
  int32_t tet_groups = 0;
  AlignedVector<int32_t> tet_point[4];
  AlignedVector<double> tet_gradient[4][3];
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

// The passes of one product, each over groups [first, last) (of points or
// of tets), on one target:
struct GatherKernels {
  // out (3 per point, interleaved as p): the per-point gather above.
  void (*product)(const GatherStreams& s, const GatherTerms& terms, const double* p, double* out, int32_t first,
                  int32_t last);
  // out[t] = scale[t] factor sum_c dV_t/dx_c . p_c (scale null: 1, factor 1).
  void (*tet_dots)(const GatherStreams& s, const double* p, const double* scale, double factor, double* out,
                   int32_t first, int32_t last);
  // out[i] = k[i] (sum over i's corners of tet[t]) / 4: the nodal term's k_a (dV_a . p).
  void (*node_sums)(const GatherStreams& s, const double* tet, const double* k, double* out, int32_t first,
                    int32_t last);
  // out[t] = factor (node[c0] + node[c1] + node[c2] + node[c3]) / 4.
  void (*tet_means)(const GatherStreams& s, const double* node, double factor, double* out, int32_t first,
                    int32_t last);
};

// The passes compiled for `target` (one of simd_targets_supported()).
const GatherKernels& implicit_gather_for(const SimdTarget& target);

}  // namespace organsim
