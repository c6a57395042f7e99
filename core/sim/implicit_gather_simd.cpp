// implicit_gather_simd.h's gather, one source compiled once per target
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

// base[idx[l]] for kLanes int32 indices.
HWY_INLINE VD gather(const double* base, const int32_t* idx) {
  const hn::Rebind<int32_t, D> di32;
  const hn::Rebind<int64_t, D> di64;
  return hn::GatherIndex(D(), base, hn::PromoteTo(di64, hn::LoadU(di32, idx)));
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

}  // namespace organsim::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include "core/util/error.h"

namespace organsim {

namespace {

struct Entry {
  int64_t bits;
  GatherGroups gather;
};
#define ORGANSIM_ENTRY(TARGET, NS) Entry{TARGET, &NS::gather_groups},
const Entry kEntries[] = {ORGANSIM_COMPILED_TARGETS(ORGANSIM_ENTRY)};
#undef ORGANSIM_ENTRY

}  // namespace

GatherGroups implicit_gather_for(const SimdTarget& target) {
  for (const Entry& e : kEntries)
    if (e.bits == target.bits) return e.gather;
  throw Error(ErrorKind::Backend, "implicit gather: target " + target.name + " is not compiled into this binary");
}

}  // namespace organsim

#endif  // HWY_ONCE
