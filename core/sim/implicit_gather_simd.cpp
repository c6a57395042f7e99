// implicit_gather_simd.h's passes, one source compiled once per target
// (hwy/foreach_target.h, the targets of core/sim/simd_targets.h).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "core/sim/implicit_gather_simd.cpp"
// The targets before foreach_target.h (which re-includes this file once per
// target), in this order: not for clang-format to sort.
// clang-format off
#include "core/sim/simd_targets.h"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"
// clang-format on

#include "core/sim/implicit_gather_simd.h"

HWY_BEFORE_NAMESPACE();
namespace organsim::HWY_NAMESPACE {
namespace {

namespace hn = hwy::HWY_NAMESPACE;
using D = hn::ScalableTag<double>;
using VD = hn::Vec<D>;
constexpr int32_t kLanes = static_cast<int32_t>(hn::MaxLanes(D()));
static_assert(kGatherGroup % kLanes == 0, "a group is whole registers on every target");

using DI32 = hn::Rebind<int32_t, D>;
using DI64 = hn::Rebind<int64_t, D>;

// base[idx[l]] for kLanes int32 indices.
HWY_INLINE VD gather(const double* base, const int32_t* idx) {
  return hn::GatherIndex(D(), base, hn::PromoteTo(DI64(), hn::LoadU(DI32(), idx)));
}

// The lanes' points first .. first + kLanes - 1, lane offset `lane` in the
// group's slot rows.
HWY_INLINE void gather_register(const GatherStreams& s, const GatherTerms& t, const double* p, double* out,
                                int32_t group, int32_t lane) {
  const D d;
  const int32_t first = kGatherGroup * group + lane;
  VD px, py, pz;
  hn::LoadInterleaved3(d, p + 3 * static_cast<size_t>(first), px, py, pz);
  const VD mass = hn::Mul(hn::Set(d, t.mass_coef), hn::LoadU(d, t.mass + first));
  VD yx = hn::Mul(mass, px), yy = hn::Mul(mass, py), yz = hn::Mul(mass, pz);
  const VD alpha = hn::Set(d, t.alpha), beta = hn::Set(d, t.beta);
  for (int32_t row = s.spring_row[group]; row < s.spring_row[group + 1]; ++row) {
    const size_t k = static_cast<size_t>(kGatherGroup) * row + lane;
    const int32_t* other = s.other3.data() + k;
    const VD dx = hn::Sub(px, gather(p, other)), dy = hn::Sub(py, gather(p + 1, other)),
             dz = hn::Sub(pz, gather(p + 2, other));
    const VD ux = hn::Load(d, s.u[0].data() + k), uy = hn::Load(d, s.u[1].data() + k),
             uz = hn::Load(d, s.u[2].data() + k);
    // (alpha d + beta axial) (u . dp) u + beta transverse dp, as the scalar gather groups it.
    const VD along =
        hn::Mul(hn::MulAdd(alpha, hn::Load(d, s.damper.data() + k), hn::Mul(beta, hn::Load(d, s.axial.data() + k))),
                hn::MulAdd(uz, dz, hn::MulAdd(uy, dy, hn::Mul(ux, dx))));
    const VD across = hn::Mul(beta, hn::Load(d, s.transverse.data() + k));
    yx = hn::Add(yx, hn::MulAdd(along, ux, hn::Mul(across, dx)));
    yy = hn::Add(yy, hn::MulAdd(along, uy, hn::Mul(across, dy)));
    yz = hn::Add(yz, hn::MulAdd(along, uz, hn::Mul(across, dz)));
  }
  if (t.volume)
    for (int32_t row = s.corner_row[group]; row < s.corner_row[group + 1]; ++row) {
      const size_t k = static_cast<size_t>(kGatherGroup) * row + lane;
      const VD c = gather(t.tet_coef, s.corner_tet.data() + k);
      yx = hn::MulAdd(c, hn::Load(d, s.gradient[0].data() + k), yx);
      yy = hn::MulAdd(c, hn::Load(d, s.gradient[1].data() + k), yy);
      yz = hn::MulAdd(c, hn::Load(d, s.gradient[2].data() + k), yz);
    }
  hn::StoreInterleaved3(yx, yy, yz, d, out + 3 * static_cast<size_t>(first));
}

}  // namespace

void gather_groups(const GatherStreams& s, const GatherTerms& terms, const double* p, double* out, int32_t first,
                   int32_t last) {
  for (int32_t g = first; g < last; ++g)
    for (int32_t lane = 0; lane < kGatherGroup; lane += kLanes) gather_register(s, terms, p, out, g, lane);
}

// The volume term's scalars, each sum in the scalar code's order
// (ImplicitSystem::apply): corner by corner, x, y, z.
void tet_dots(const GatherStreams& s, const double* p, const double* scale, double factor, double* out, int32_t first,
              int32_t last) {
  const D d;
  for (int32_t e = kGatherGroup * first; e < kGatherGroup * last; e += kLanes) {
    VD sum = hn::Zero(d);
    for (int c = 0; c < 4; ++c) {
      const auto i = hn::LoadU(DI32(), s.tet_point[c].data() + e);
      const auto i3 = hn::PromoteTo(DI64(), hn::Add(i, hn::Add(i, i)));
      VD dot = hn::Mul(hn::Load(d, s.tet_gradient[c][0].data() + e), hn::GatherIndex(d, p, i3));
      dot = hn::MulAdd(hn::Load(d, s.tet_gradient[c][1].data() + e), hn::GatherIndex(d, p + 1, i3), dot);
      dot = hn::MulAdd(hn::Load(d, s.tet_gradient[c][2].data() + e), hn::GatherIndex(d, p + 2, i3), dot);
      sum = hn::Add(sum, dot);
    }
    if (scale) sum = hn::Mul(hn::Mul(hn::Set(d, factor), hn::LoadU(d, scale + e)), sum);
    hn::StoreU(sum, d, out + e);
  }
}

void node_sums(const GatherStreams& s, const double* tet, const double* k, double* out, int32_t first, int32_t last) {
  const D d;
  for (int32_t g = first; g < last; ++g)
    for (int32_t lane = 0; lane < kGatherGroup; lane += kLanes) {
      VD sum = hn::Zero(d);
      for (int32_t row = s.corner_row[g]; row < s.corner_row[g + 1]; ++row)
        sum = hn::Add(sum, gather(tet, s.corner_tet.data() + static_cast<size_t>(kGatherGroup) * row + lane));
      const int32_t i = kGatherGroup * g + lane;
      hn::StoreU(hn::Mul(hn::Mul(hn::LoadU(d, k + i), sum), hn::Set(d, 0.25)), d, out + i);
    }
}

void tet_means(const GatherStreams& s, const double* node, double factor, double* out, int32_t first, int32_t last) {
  const D d;
  for (int32_t e = kGatherGroup * first; e < kGatherGroup * last; e += kLanes) {
    VD sum = gather(node, s.tet_point[0].data() + e);
    for (int c = 1; c < 4; ++c) sum = hn::Add(sum, gather(node, s.tet_point[c].data() + e));
    hn::StoreU(hn::Mul(hn::Mul(hn::Set(d, factor), sum), hn::Set(d, 0.25)), d, out + e);
  }
}

}  // namespace organsim::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "core/util/error.h"

namespace organsim {

namespace {

struct Entry {
  int64_t bits;
  GatherKernels kernels;
};
#define ORGANSIM_ENTRY(TARGET, NS) Entry{TARGET, {&NS::gather_groups, &NS::tet_dots, &NS::node_sums, &NS::tet_means}},
const Entry kEntries[] = {ORGANSIM_COMPILED_TARGETS(ORGANSIM_ENTRY)};
#undef ORGANSIM_ENTRY

}  // namespace

const GatherKernels& implicit_gather_for(const SimdTarget& target) {
  for (const Entry& e : kEntries)
    if (e.bits == target.bits) return e.kernels;
  throw Error(ErrorKind::Backend, "implicit gather: target " + target.name + " is not compiled into this binary");
}

}  // namespace organsim

#endif  // HWY_ONCE
