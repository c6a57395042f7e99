// The SIMD kernel's registers, point records and their in-register
// transposes (cpu_kernel_simd.cpp), written once on Google Highway for
// every target it is compiled for: one register of Real lanes (4 floats on
// SSE4 and NEON, 8 on AVX2, 16 on AVX-512; half as many doubles).
//
// Neighbours are read with plain 16-byte loads of their records, combined
// into registers and transposed in registers, because a hardware gather
// costs several times more on most x86 cores (and SSE4 and NEON have none).
// Everything is built of 16-byte blocks, the unit every target's shuffles
// work in: a block holds 4 floats or 2 doubles of one record.
//
// Layouts (one set for every target):
//   float:  one 32-byte record per point, (x, y, z, w, dx, dy, dz, 0): a
//           spring's neighbour is one cache line's half;
//   double: positions (x, y, z, w) and increments (dx, dy, dz, 0) in two
//           arrays of 32-byte quads: the tet pass reads positions only.
// w is the nodal volume term's scaled pressure, 0 without it. The
// displacement records of the shear element have the same layouts; their
// increment's 4th value carries the smoothed stress's P_22. Force arrays
// are (x, y, z, 0) per point in both precisions.
//
// Included once per target by cpu_kernel_simd.cpp (Highway's
// foreach_target.h), hence the toggling include guard.
#if defined(ORGANSIM_SIMD_RECORDS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef ORGANSIM_SIMD_RECORDS_INL_H_
#undef ORGANSIM_SIMD_RECORDS_INL_H_
#else
#define ORGANSIM_SIMD_RECORDS_INL_H_
#endif

#include <cstddef>
#include <cstdint>

#include "hwy/highway.h"

HWY_BEFORE_NAMESPACE();
namespace organsim::HWY_NAMESPACE {

namespace hn = hwy::HWY_NAMESPACE;

template <class Real>
using Tag = hn::ScalableTag<Real>;
template <class Real>
using V = hn::Vec<Tag<Real>>;
template <class Real>
using MaskOf = hn::Mask<Tag<Real>>;
template <class Real>
using V3 = V<Real>[3];
template <class Real>
using V33 = V<Real>[3][3];

// Lanes per register, and per 16-byte block.
template <class Real>
inline constexpr int32_t kLanes = static_cast<int32_t>(hn::MaxLanes(Tag<Real>()));
template <class Real>
inline constexpr int32_t kPerBlock = 16 / static_cast<int32_t>(sizeof(Real));

template <class Real>
HWY_INLINE V<Real> load(const Real* p) {
  return hn::Load(Tag<Real>(), p);
}
template <class Real>
HWY_INLINE void store(Real* p, V<Real> a) {
  hn::Store(a, Tag<Real>(), p);
}
template <class Real>
HWY_INLINE V<Real> splat(Real a) {
  return hn::Set(Tag<Real>(), a);
}
template <class Real>
HWY_INLINE V<Real> zero() {
  return hn::Zero(Tag<Real>());
}
// a b + c, a b - c, c - a b (fused where the target has FMA).
template <class VV>
HWY_INLINE VV fmadd(VV a, VV b, VV c) {
  return hn::MulAdd(a, b, c);
}
template <class VV>
HWY_INLINE VV fmsub(VV a, VV b, VV c) {
  return hn::MulSub(a, b, c);
}
template <class VV>
HWY_INLINE VV fnmadd(VV a, VV b, VV c) {
  return hn::NegMulAdd(a, b, c);
}
// Lanes of a where m is set, b elsewhere; a where m is set, zero elsewhere.
// Highway's one-lane SCALAR target selects with a branch, which data such
// as a suture's slack or taut state mispredicts (the sutured step took
// 1.8x the unsutured one there); the mask's bits select without one.
template <class M, class VV>
HWY_INLINE VV select(M m, VV a, VV b) {
#if HWY_TARGET == HWY_SCALAR
  const auto bits = hn::VecFromMask(hn::DFromV<VV>(), m);
  return hn::Or(hn::And(bits, a), hn::AndNot(bits, b));
#else
  return hn::IfThenElse(m, a, b);
#endif
}
template <class M, class VV>
HWY_INLINE VV keep(M m, VV a) {
#if HWY_TARGET == HWY_SCALAR
  return hn::And(hn::VecFromMask(hn::DFromV<VV>(), m), a);
#else
  return hn::IfThenElseZero(m, a);
#endif
}

// 1/|l| for |l|^2 = len2 > 0, 0 otherwise (padding, coincident ends): the
// target's estimate and Newton steps y (1.5 - x y^2 / 2) to full precision
// (a division and a square root cost several times more). The rest lengths
// are computed by this same function, so the rest state is force-free.
HWY_INLINE V<float> newton_rsqrt(V<float> half_x, V<float> y) {
  return y * fnmadd(half_x * y, y, splat(1.5f));
}
HWY_INLINE V<double> newton_rsqrt(V<double> half_x, V<double> y) {
  return y * fnmadd(half_x * y, y, splat(1.5));
}
// The float estimate: 14 bits on AVX-512, 12 on SSE4 and AVX2 (one Newton
// step: full float precision); 8 on NEON and ~10 from the portable
// targets' bit trick (two steps).
template <class DF>
HWY_INLINE hn::Vec<DF> rsqrt_float(DF df, hn::Vec<DF> len2) {
  const auto half_x = hn::Mul(len2, hn::Set(df, 0.5f));
  auto y = hn::IfThenElseZero(hn::Gt(len2, hn::Zero(df)), hn::ApproximateReciprocalSqrt(len2));
  y = hn::Mul(y, hn::NegMulAdd(hn::Mul(half_x, y), y, hn::Set(df, 1.5f)));
#if HWY_TARGET == HWY_NEON || HWY_TARGET == HWY_EMU128 || HWY_TARGET == HWY_SCALAR
  y = hn::Mul(y, hn::NegMulAdd(hn::Mul(half_x, y), y, hn::Set(df, 1.5f)));
#endif
  return y;
}
HWY_INLINE V<float> inv_length(V<float> len2) { return rsqrt_float(Tag<float>(), len2); }
HWY_INLINE V<double> inv_length(V<double> len2) {
  const Tag<double> d;
  const V<double> half_x = splat(0.5) * len2;
#if HWY_TARGET == HWY_AVX3
  // AVX-512 has a 14-bit estimate in double: two steps (14 -> 28 -> 56 bits).
  V<double> y{_mm512_maskz_rsqrt14_pd(_mm512_cmp_pd_mask(len2.raw, _mm512_setzero_pd(), _CMP_GT_OQ), len2.raw)};
  (void)d;
#else
  // Elsewhere the float estimate (with its steps, ~23 bits), then two
  // steps in double (-> 46 -> 92 bits). Lengths of springs fit in float's range.
  const hn::Rebind<float, Tag<double>> df;
  V<double> y = hn::PromoteTo(d, rsqrt_float(df, hn::DemoteTo(df, len2)));
  y = hn::IfThenElseZero(hn::Gt(len2, hn::Zero(d)), y);
#endif
  y = newton_rsqrt(half_x, y);
  return newton_rsqrt(half_x, y);
}

// Lanes of int32 indices from an int32 array: whether each is >= 0.
HWY_INLINE MaskOf<float> nonnegative(const int32_t* a, float) {
  const hn::RebindToSigned<Tag<float>> di;
  return hn::RebindMask(Tag<float>(), hn::Gt(hn::LoadU(di, a), hn::Set(di, -1)));
}
HWY_INLINE MaskOf<double> nonnegative(const int32_t* a, double) {
  const hn::Rebind<int32_t, Tag<double>> di32;
  const hn::Rebind<int64_t, Tag<double>> di64;
  return hn::RebindMask(Tag<double>(), hn::Gt(hn::PromoteTo(di64, hn::LoadU(di32, a)), hn::Set(di64, int64_t{-1})));
}

// base[idx[l]] for the lanes' int32 indices (a hardware gather where the
// target has one): for the few per-point sums that read one value per slot.
HWY_INLINE V<float> gather_at(const float* base, const int32_t* idx) {
  const hn::RebindToSigned<Tag<float>> di;
  return hn::GatherIndex(Tag<float>(), base, hn::Load(di, idx));
}
HWY_INLINE V<double> gather_at(const double* base, const int32_t* idx) {
  const hn::Rebind<int32_t, Tag<double>> di32;
  const hn::Rebind<int64_t, Tag<double>> di64;
  return hn::GatherIndex(Tag<double>(), base, hn::PromoteTo(di64, hn::LoadU(di32, idx)));
}

// ---- 16-byte blocks -----------------------------------------------------------
// Highway's SCALAR target (one lane, the portable fallback where EMU128 is
// not built) has no blocks: there the records are read and written a value
// at a time (ORGANSIM_SIMD_NARROW).
#undef ORGANSIM_SIMD_NARROW
#undef ORGANSIM_SIMD_AVX3
#if HWY_TARGET == HWY_SCALAR
#define ORGANSIM_SIMD_NARROW 1
#else
#define ORGANSIM_SIMD_NARROW 0

// A register of d whose block k is the 16 bytes at p[k].
template <class D>
HWY_INLINE hn::Vec<D> load_blocks(D d, const hn::TFromD<D>* const* p) {
  constexpr size_t kBlocks = hn::MaxLanes(D()) * sizeof(hn::TFromD<D>) / 16;
  if constexpr (kBlocks == 1) {
    return hn::LoadU(d, p[0]);
  } else {
    const hn::Half<D> dh;
    return hn::Combine(d, load_blocks(dh, p + kBlocks / 2), load_blocks(dh, p));
  }
}

// Block k of v into out[k].
template <class D>
HWY_INLINE void split_blocks(D d, hn::Vec<D> v, hn::Vec<hn::Full128<hn::TFromD<D>>>* out) {
  constexpr size_t kBlocks = hn::MaxLanes(D()) * sizeof(hn::TFromD<D>) / 16;
  if constexpr (kBlocks == 1) {
    (void)d;
    out[0] = v;
  } else {
    const hn::Half<D> dh;
    split_blocks(dh, hn::LowerHalf(dh, v), out);
    split_blocks(dh, hn::UpperHalf(dh, v), out + kBlocks / 2);
  }
}

// Transposes inside every block: out[j] lane (block k, i) = r[i] lane
// (block k, j). 4 x 4 in float, 2 x 2 in double; its own inverse.
HWY_INLINE void transpose_blocks(const V<float> (&r)[4], V<float> (&out)[4]) {
  const Tag<float> d;
  const hn::Repartition<double, Tag<float>> d64;
  const V<float> t0 = hn::InterleaveLower(d, r[0], r[1]), t1 = hn::InterleaveUpper(d, r[0], r[1]);
  const V<float> t2 = hn::InterleaveLower(d, r[2], r[3]), t3 = hn::InterleaveUpper(d, r[2], r[3]);
  auto lo = [&](V<float> a, V<float> b) {
    return hn::BitCast(d, hn::InterleaveLower(d64, hn::BitCast(d64, a), hn::BitCast(d64, b)));
  };
  auto hi = [&](V<float> a, V<float> b) {
    return hn::BitCast(d, hn::InterleaveUpper(d64, hn::BitCast(d64, a), hn::BitCast(d64, b)));
  };
  out[0] = lo(t0, t2), out[1] = hi(t0, t2), out[2] = lo(t1, t3), out[3] = hi(t1, t3);
}
HWY_INLINE void transpose_blocks(const V<double> (&r)[2], V<double> (&out)[2]) {
  const Tag<double> d;
  out[0] = hn::InterleaveLower(d, r[0], r[1]);
  out[1] = hn::InterleaveUpper(d, r[0], r[1]);
}

// Values v0.. v0 + kPerBlock - 1 of the records at base + Scale q[l] (one
// block of each), value j of every lane in out[j], lanes in q order:
// register i holds the blocks of lanes kPerBlock k + i.
template <int Scale, class Real>
HWY_INLINE void gather_block(const Real* base, const int32_t* q, int v0, V<Real> (&out)[kPerBlock<Real>]) {
  constexpr int32_t P = kPerBlock<Real>, B = kLanes<Real> / P;
  V<Real> r[P];
  for (int32_t i = 0; i < P; ++i) {
    // 64-bit offsets, so that the scaling folds into the load's addressing.
    const Real* p[B];
    for (int32_t k = 0; k < B; ++k) p[k] = base + Scale * static_cast<ptrdiff_t>(q[P * k + i]) + v0;
    r[i] = load_blocks(Tag<Real>(), p);
  }
  transpose_blocks(r, out);
}

#endif  // blocks

// ---- 256-bit quads of doubles (AVX2 and AVX-512) ------------------------------
// A double record is one 32-byte quad: on targets with 256-bit registers
// four points are read with one load each and a 4 x 4 transpose, and a
// force is added with one 256-bit load, add and store, where the generic
// block code needs two of each. In Highway's ops on 256-bit vectors, which
// these targets have (AVX2's full register, half of AVX-512's).
#if HWY_TARGET == HWY_AVX2 || HWY_TARGET == HWY_AVX3
using QuadTag = hn::Full256<double>;
using Quad = hn::Vec<QuadTag>;

// The 4 x 4 transpose, its own inverse: lane i of out[j] is lane j of
// in[i] (interleaves inside the 128-bit blocks, then block swaps).
HWY_INLINE void quad_transpose(const Quad (&in)[4], Quad (&out)[4]) {
  const QuadTag d;
  // t0 = (a0 b0 | a2 b2), t1 = (a1 b1 | a3 b3) for rows a, b = in[0], in[1]; t2, t3 for in[2], in[3].
  const Quad t0 = hn::InterleaveLower(d, in[0], in[1]), t1 = hn::InterleaveUpper(d, in[0], in[1]);
  const Quad t2 = hn::InterleaveLower(d, in[2], in[3]), t3 = hn::InterleaveUpper(d, in[2], in[3]);
  out[0] = hn::ConcatLowerLower(d, t2, t0);
  out[1] = hn::ConcatLowerLower(d, t3, t1);
  out[2] = hn::ConcatUpperUpper(d, t2, t0);
  out[3] = hn::ConcatUpperUpper(d, t3, t1);
}

// (x, y, z, w) of the quads at base + Scale q[0..3], value j of point i in
// lane i of out[j].
template <int Scale>
HWY_INLINE void quad_gather4(const double* base, const int32_t* q, Quad (&out)[4]) {
  const QuadTag d;
  Quad r[4];
  for (int i = 0; i < 4; ++i) r[i] = hn::LoadU(d, base + Scale * static_cast<ptrdiff_t>(q[i]));
  quad_transpose(r, out);
}

// The sums of the forces (x, y, z, 0) at force + q[i] and lane i of x, y,
// z, into sum[0..3].
HWY_INLINE void quad_add_forces(const double* force, const int32_t* q, Quad x, Quad y, Quad z, Quad* sum) {
  const QuadTag d;
  const Quad rows[4] = {x, y, z, hn::Zero(d)};
  Quad quad[4];
  quad_transpose(rows, quad);
  for (int i = 0; i < 4; ++i) sum[i] = hn::Add(hn::LoadU(d, force + q[i]), quad[i]);
}
#endif

// AVX2's double records in those quads (AVX-512's own are below).
#undef ORGANSIM_SIMD_AVX2
#if HWY_TARGET == HWY_AVX2
#define ORGANSIM_SIMD_AVX2 1
// Adds lane l of (x, y, z) to the 32-byte force of point q[l]; all four
// loaded before any is stored.
HWY_INLINE void avx2_scatter_add(double* force, const int32_t* q, const V<double> (&f)[3]) {
  Quad sum[4];
  quad_add_forces(force, q, f[0], f[1], f[2], sum);
  for (int i = 0; i < 4; ++i) hn::StoreU(sum[i], QuadTag(), force + q[i]);
}
#else
#define ORGANSIM_SIMD_AVX2 0
#endif

// ---- AVX-512 specialisations ----------------------------------------------------
// The record reads and writes in AVX-512's own shuffles (two-source
// permutes, whole 32-byte records per load, a 512-bit store of two
// records), which the generic block code cannot express: together 4 %
// faster in float than that code on an AMD EPYC (Zen 5), the same in double.
#if HWY_TARGET == HWY_AVX3
#define ORGANSIM_SIMD_AVX3 1

// (x, y, z, w) of 8 points from their 32-byte quads at base + Scale q[i]:
// four registers of two quads each. Register i holds quads (q_a, q_b) with
// (a, b) = (0, 2), (1, 3), (4, 6), (5, 7), so that the shuffles leave lanes
// in q order.
template <int Scale>
HWY_INLINE void avx3_gather4(const double* base, const int32_t* q, V<double> (&a)[4]) {
  auto pair = [&](int i, int j) {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_loadu_pd(base + Scale * static_cast<ptrdiff_t>(q[i]))),
                              _mm256_loadu_pd(base + Scale * static_cast<ptrdiff_t>(q[j])), 1);
  };
  const __m512d r0 = pair(0, 2), r1 = pair(1, 3), r2 = pair(4, 6), r3 = pair(5, 7);
  // t0 = (x0 x1 | z0 z1 | x2 x3 | z2 z3), t1 = (y0 y1 | w0 w1 | ...), t2, t3 likewise for 4..7.
  const __m512d t0 = _mm512_unpacklo_pd(r0, r1), t1 = _mm512_unpackhi_pd(r0, r1);
  const __m512d t2 = _mm512_unpacklo_pd(r2, r3), t3 = _mm512_unpackhi_pd(r2, r3);
  a[0].raw = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(2, 0, 2, 0));
  a[1].raw = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(2, 0, 2, 0));
  a[2].raw = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(3, 1, 3, 1));
  a[3].raw = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(3, 1, 3, 1));
}

// All eight floats of 16 points' 32-byte records: eight registers of two
// records each. Register i holds records (q_i, q_{i+4}) for i < 4 and
// (q_{i+4}, q_{i+8}) above, so that the shuffles leave lanes in q order.
template <int Scale>
HWY_INLINE void avx3_gather8(const float* rec, const int32_t* q, V<float> (&a)[8]) {
  auto pair = [&](int i, int j) {
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(rec + Scale * static_cast<ptrdiff_t>(q[i]))),
                              _mm256_loadu_ps(rec + Scale * static_cast<ptrdiff_t>(q[j])), 1);
  };
  const __m512 r0 = pair(0, 4), r1 = pair(1, 5), r2 = pair(2, 6), r3 = pair(3, 7);
  const __m512 r4 = pair(8, 12), r5 = pair(9, 13), r6 = pair(10, 14), r7 = pair(11, 15);
  const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  const __m512 t4 = _mm512_unpacklo_ps(r4, r5), t5 = _mm512_unpackhi_ps(r4, r5);
  const __m512 t6 = _mm512_unpacklo_ps(r6, r7), t7 = _mm512_unpackhi_ps(r6, r7);
  // Per 128-bit quarter: value j of 4 points, then value j + 4 of the same 4.
  const __m512 s0[4] = {_mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2)),
                        _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2))};
  const __m512 s1[4] = {_mm512_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2)),
                        _mm512_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(t5, t7, _MM_SHUFFLE(3, 2, 3, 2))};
  for (int j = 0; j < 4; ++j) {
    a[j].raw = _mm512_shuffle_f32x4(s0[j], s1[j], _MM_SHUFFLE(2, 0, 2, 0));
    a[j + 4].raw = _mm512_shuffle_f32x4(s0[j], s1[j], _MM_SHUFFLE(3, 1, 3, 1));
  }
}

// Adds lane l of (x, y, z) to the 32-byte force of point q[l], made per
// 256-bit half; all eight loaded before any is stored.
HWY_INLINE void avx3_scatter_add(double* force, const int32_t* q, const V<double> (&f)[3]) {
  const QuadTag dh;
  Quad sum[8];
  quad_add_forces(force, q, hn::LowerHalf(dh, f[0]), hn::LowerHalf(dh, f[1]), hn::LowerHalf(dh, f[2]), sum);
  quad_add_forces(force, q + 4, hn::UpperHalf(dh, f[0]), hn::UpperHalf(dh, f[1]), hn::UpperHalf(dh, f[2]), sum + 4);
  for (int l = 0; l < 8; ++l) hn::StoreU(sum[l], dh, force + q[l]);
}

// The records (x, y, z, 0, dx, dy, dz, 0) of 16 consecutive points: each
// 512-bit store holds two consecutive records.
HWY_INLINE void avx3_store_records(float* rec, const V<float> (&x)[3], const V<float> (&d)[3]) {
  // Quarter k of s holds lane k of points (p, p+2, p+4, p+6) in the order
  // position, increment, position of the next point, its increment.
  const __m512i lo = _mm512_setr_epi32(0, 2, 4, 6, 16, 18, 20, 22, 1, 3, 5, 7, 17, 19, 21, 23);
  const __m512i hi = _mm512_add_epi32(lo, _mm512_set1_epi32(8));
  const __m512 zero = _mm512_setzero_ps();
  for (int half = 0; half < 2; ++half) {
    const __m512i idx = half ? hi : lo;
    const __m512 sx = _mm512_permutex2var_ps(x[0].raw, idx, d[0].raw);
    const __m512 sy = _mm512_permutex2var_ps(x[1].raw, idx, d[1].raw);
    const __m512 sz = _mm512_permutex2var_ps(x[2].raw, idx, d[2].raw);
    const __m512 u0 = _mm512_unpacklo_ps(sx, sy), u1 = _mm512_unpackhi_ps(sx, sy);
    const __m512 u2 = _mm512_unpacklo_ps(sz, zero), u3 = _mm512_unpackhi_ps(sz, zero);
    float* out = rec + 64 * half;
    _mm512_store_ps(out + 0, _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)));
    _mm512_store_ps(out + 16, _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)));
    _mm512_store_ps(out + 32, _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)));
    _mm512_store_ps(out + 48, _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2)));
  }
}
// Adds lane l of (x, y, z) to the 16-byte force of point q[l]: quarter k of
// r[i] is (x, y, z, 0) of lane 4k + i; all 16 loaded before any is stored.
HWY_INLINE void avx3_scatter_add(float* force, const int32_t* q, const V<float> (&f)[3]) {
  const __m512 zero = _mm512_setzero_ps();
  const __m512 u0 = _mm512_unpacklo_ps(f[0].raw, f[1].raw), u1 = _mm512_unpackhi_ps(f[0].raw, f[1].raw);
  const __m512 u2 = _mm512_unpacklo_ps(f[2].raw, zero), u3 = _mm512_unpackhi_ps(f[2].raw, zero);
  const __m512 r[4] = {_mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)),
                       _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2))};
  __m128 sum[16];
  for (int i = 0; i < 4; ++i) {
    sum[i] = _mm_add_ps(_mm_loadu_ps(force + q[i]), _mm512_castps512_ps128(r[i]));
    sum[4 + i] = _mm_add_ps(_mm_loadu_ps(force + q[4 + i]), _mm512_extractf32x4_ps(r[i], 1));
    sum[8 + i] = _mm_add_ps(_mm_loadu_ps(force + q[8 + i]), _mm512_extractf32x4_ps(r[i], 2));
    sum[12 + i] = _mm_add_ps(_mm_loadu_ps(force + q[12 + i]), _mm512_extractf32x4_ps(r[i], 3));
  }
  for (int l = 0; l < 16; ++l) _mm_storeu_ps(force + q[l], sum[l]);
}

// Adds the 16-byte forces of 16 consecutive points to f and clears them.
HWY_INLINE void avx3_take_forces(float* force, V<float> (&f)[3]) {
  const __m512 l0 = _mm512_load_ps(force), l1 = _mm512_load_ps(force + 16), l2 = _mm512_load_ps(force + 32),
               l3 = _mm512_load_ps(force + 48);
  const __m512i ix = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 0, 4, 8, 12, 16, 20, 24, 28);
  for (int k = 0; k < 3; ++k) {
    const __m512i idx = _mm512_add_epi32(ix, _mm512_set1_epi32(k));
    f[k].raw = _mm512_add_ps(f[k].raw, _mm512_shuffle_f32x4(_mm512_permutex2var_ps(l0, idx, l1),
                                                            _mm512_permutex2var_ps(l2, idx, l3), _MM_SHUFFLE(1, 0, 1, 0)));
  }
  for (int i = 0; i < 4; ++i) _mm512_store_ps(force + 16 * i, _mm512_setzero_ps());
}

// Adds the 32-byte forces of 8 consecutive points to f and clears them.
HWY_INLINE void avx3_take_forces(double* force, V<double> (&f)[3]) {
  const __m512d l0 = _mm512_load_pd(force), l1 = _mm512_load_pd(force + 8), l2 = _mm512_load_pd(force + 16),
                l3 = _mm512_load_pd(force + 24);
  // From two registers of quads (points i..i+3): (x_i..x_i+3, y_i..y_i+3) and (z_i..z_i+3, -).
  const __m512i xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
  const __m512i z_ = _mm512_setr_epi64(2, 6, 10, 14, 2, 6, 10, 14);
  const __m512d xy0 = _mm512_permutex2var_pd(l0, xy, l1), xy1 = _mm512_permutex2var_pd(l2, xy, l3);
  const __m512d z0 = _mm512_permutex2var_pd(l0, z_, l1), z1 = _mm512_permutex2var_pd(l2, z_, l3);
  f[0].raw = _mm512_add_pd(f[0].raw, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(1, 0, 1, 0)));
  f[1].raw = _mm512_add_pd(f[1].raw, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(3, 2, 3, 2)));
  f[2].raw = _mm512_add_pd(f[2].raw, _mm512_shuffle_f64x2(z0, z1, _MM_SHUFFLE(1, 0, 1, 0)));
  for (int i = 0; i < 4; ++i) _mm512_store_pd(force + 8 * i, _mm512_setzero_pd());
}
#else
#define ORGANSIM_SIMD_AVX3 0
#endif

// The first NV values (a multiple of 4) of the records at base + Scale q[l].
template <int Scale, int NV, class Real>
HWY_INLINE void gather_values(const Real* base, const int32_t* q, V<Real> (&a)[NV]) {
  constexpr int32_t P = kPerBlock<Real>, N = kLanes<Real>;
#if ORGANSIM_SIMD_NARROW
  (void)P;
  alignas(16) Real lanes[NV][N];
  for (int32_t l = 0; l < N; ++l)
    for (int j = 0; j < NV; ++j) lanes[j][l] = base[Scale * static_cast<ptrdiff_t>(q[l]) + j];
  for (int j = 0; j < NV; ++j) a[j] = load(lanes[j]);
#else
  (void)N;
  for (int v0 = 0; v0 < NV; v0 += P) {
    V<Real> out[P];
    gather_block<Scale>(base, q, v0, out);
    for (int32_t j = 0; j < P; ++j) a[v0 + j] = out[j];
  }
#endif
}

#if !ORGANSIM_SIMD_NARROW
// The inverse transpose of gather_values: out[v0 / kPerBlock][l] is the
// block of values v0.. v0 + kPerBlock - 1 of lane l, from a[j] (value j
// of every lane).
template <int R, class Real>
HWY_INLINE void lane_blocks(const V<Real> (&a)[R], hn::Vec<hn::Full128<Real>> (&out)[R / kPerBlock<Real>][kLanes<Real>]) {
  constexpr int32_t P = kPerBlock<Real>, B = kLanes<Real> / P;
  for (int v0 = 0; v0 < R; v0 += P) {
    V<Real> in[P], r[P];
    for (int32_t j = 0; j < P; ++j) in[j] = a[v0 + j];
    transpose_blocks(in, r);
    for (int32_t i = 0; i < P; ++i) {
      hn::Vec<hn::Full128<Real>> blocks[B];
      split_blocks(Tag<Real>(), r[i], blocks);
      for (int32_t k = 0; k < B; ++k) out[v0 / P][P * k + i] = blocks[k];
    }
  }
}
#endif

// The inverse for kLanes consecutive points: their records of R values
// (R a multiple of 4) at out from a[j] (value j of every lane).
template <int R, class Real>
HWY_INLINE void store_values(Real* out, const V<Real> (&a)[R]) {
  constexpr int32_t N = kLanes<Real>;
#if ORGANSIM_SIMD_NARROW
  alignas(16) Real lanes[N];
  for (int j = 0; j < R; ++j) {
    store(lanes, a[j]);
    for (int32_t l = 0; l < N; ++l) out[R * l + j] = lanes[l];
  }
#else
  constexpr int32_t P = kPerBlock<Real>;
  hn::Vec<hn::Full128<Real>> blocks[R / P][N];
  lane_blocks<R, Real>(a, blocks);
  for (int v0 = 0; v0 < R; v0 += P)
    for (int32_t l = 0; l < N; ++l) hn::StoreU(blocks[v0 / P][l], hn::Full128<Real>(), out + R * l + v0);
#endif
}

// Adds lane l of f to the (x, y, z, 0) force of point q[l] (q pre-scaled
// by 4). The lanes' points are distinct (tet_batches.h), so all forces are
// loaded before any is stored; padding lanes all point at npad, whose force
// stays zero (they add zero).
template <class Real>
HWY_INLINE void scatter_add(Real* force, const int32_t* q, const V<Real> (&f)[3]) {
#if ORGANSIM_SIMD_AVX3
  avx3_scatter_add(force, q, f);
#elif ORGANSIM_SIMD_NARROW
  constexpr int32_t N = kLanes<Real>;
  alignas(16) Real lanes[3][N];
  for (int j = 0; j < 3; ++j) store(lanes[j], f[j]);
  for (int32_t l = 0; l < N; ++l)
    for (int j = 0; j < 3; ++j) force[q[l] + j] += lanes[j][l];
#else
#if ORGANSIM_SIMD_AVX2
  if constexpr (sizeof(Real) == 8) {
    avx2_scatter_add(force, q, f);
    return;
  }
#endif
  constexpr int32_t P = kPerBlock<Real>, N = kLanes<Real>;
  const hn::Full128<Real> d128;
  const V<Real> a[4] = {f[0], f[1], f[2], zero<Real>()};
  hn::Vec<hn::Full128<Real>> sum[4 / P][N];  // per block of values, per lane
  lane_blocks<4, Real>(a, sum);
  for (int v0 = 0; v0 < 4; v0 += P)
    for (int32_t l = 0; l < N; ++l) sum[v0 / P][l] = hn::Add(hn::LoadU(d128, force + q[l] + v0), sum[v0 / P][l]);
  for (int v0 = 0; v0 < 4; v0 += P)
    for (int32_t l = 0; l < N; ++l) hn::StoreU(sum[v0 / P][l], d128, force + q[l] + v0);
#endif
}

// Adds the (x, y, z, 0) forces of kLanes consecutive points to f and clears them.
template <class Real>
HWY_INLINE void take_forces(Real* force, V<Real> (&f)[3]) {
#if ORGANSIM_SIMD_AVX3
  avx3_take_forces(force, f);
#else
  const Tag<Real> d;
  V<Real> x, y, z, w;
  hn::LoadInterleaved4(d, force, x, y, z, w);
  f[0] = f[0] + x, f[1] = f[1] + y, f[2] = f[2] + z;
  for (int32_t i = 0; i < 4; ++i) store(force + kLanes<Real> * i, zero<Real>());
#endif
}

// ---- The records of both precisions ---------------------------------------------

// Values per point in the record arrays: float keeps position and increment
// in one 8-float record, double in two arrays of 4-double quads.
template <class Real>
inline constexpr int32_t kRecord = sizeof(Real) == 4 ? 8 : 4;
template <class Real>
inline constexpr bool kSplit = kRecord<Real> == 4;

// Position and increment of the neighbours q (pre-scaled offsets; the
// records at rec + Scale q, increments at inc + Scale q when split). dw is
// the increment's 4th value (float: the record's last; double: w of the
// increment quad), which the smoothed shear pass uses for P_22.
template <int Scale, class Real>
HWY_INLINE void gather_xd(const Real* rec, const Real* inc, const int32_t* q, V3<Real>& x, V3<Real>& d, V<Real>& dw) {
  if constexpr (kSplit<Real>) {
    V<Real> a[4], b[4];
#if ORGANSIM_SIMD_AVX3
    avx3_gather4<Scale>(rec, q, a);
    avx3_gather4<Scale>(inc, q, b);
#elif ORGANSIM_SIMD_AVX2
    quad_gather4<Scale>(rec, q, a);
    quad_gather4<Scale>(inc, q, b);
#else
    gather_values<Scale, 4>(rec, q, a);
    gather_values<Scale, 4>(inc, q, b);
#endif
    for (int k = 0; k < 3; ++k) x[k] = a[k], d[k] = b[k];
    dw = b[3];
  } else {
    (void)inc;
    V<Real> a[8];
#if ORGANSIM_SIMD_AVX3
    avx3_gather8<Scale>(rec, q, a);
#else
    gather_values<Scale, 8>(rec, q, a);
#endif
    for (int k = 0; k < 3; ++k) x[k] = a[k], d[k] = a[4 + k];
    dw = a[7];
  }
}
template <int Scale, class Real>
HWY_INLINE void gather_xd(const Real* rec, const Real* inc, const int32_t* q, V3<Real>& x, V3<Real>& d) {
  V<Real> unused;
  gather_xd<Scale>(rec, inc, q, x, d, unused);
}
// Position with w, and position only (the unused shuffles are dropped by the compiler).
template <int Scale, class Real>
HWY_INLINE void gather_xw(const Real* rec, const int32_t* q, V3<Real>& x, V<Real>& w) {
  V<Real> a[4];
#if ORGANSIM_SIMD_AVX3
  if constexpr (sizeof(Real) == 8) avx3_gather4<Scale>(rec, q, a);
  else gather_values<Scale, 4>(rec, q, a);
#elif ORGANSIM_SIMD_AVX2
  if constexpr (sizeof(Real) == 8) quad_gather4<Scale>(rec, q, a);
  else gather_values<Scale, 4>(rec, q, a);
#else
  gather_values<Scale, 4>(rec, q, a);
#endif
  for (int k = 0; k < 3; ++k) x[k] = a[k];
  w = a[3];
}
template <int Scale, class Real>
HWY_INLINE void gather_x(const Real* rec, const int32_t* q, V3<Real>& x) {
  V<Real> unused;
  gather_xw<Scale>(rec, q, x, unused);
}

// The records of the points p0.. (one register of lanes): (x, 0 [, d, 0])
// in one array, or x and d quads in two.
template <class Real>
HWY_INLINE void store_records(Real* rec, Real* inc, int32_t p0, const V3<Real>& x, const V3<Real>& d) {
  const V<Real> z = zero<Real>();
  if constexpr (kSplit<Real>) {
    const Tag<Real> t;
    hn::StoreInterleaved4(x[0], x[1], x[2], z, t, rec + 4 * static_cast<size_t>(p0));
    hn::StoreInterleaved4(d[0], d[1], d[2], z, t, inc + 4 * static_cast<size_t>(p0));
  } else {
    (void)inc;
#if ORGANSIM_SIMD_AVX3
    avx3_store_records(rec + 8 * static_cast<size_t>(p0), x, d);
#else
    const V<Real> a[8] = {x[0], x[1], x[2], z, d[0], d[1], d[2], z};
    store_values<8>(rec + 8 * static_cast<size_t>(p0), a);
#endif
  }
}
// The positions only (split layouts), the whole records otherwise.
template <class Real>
HWY_INLINE void store_positions(Real* rec, int32_t p0, const V3<Real>& x, const V3<Real>& d) {
  if constexpr (kSplit<Real>) {
    const V<Real> z = zero<Real>();
    hn::StoreInterleaved4(x[0], x[1], x[2], z, Tag<Real>(), rec + 4 * static_cast<size_t>(p0));
  } else {
    store_records(rec, static_cast<Real*>(nullptr), p0, x, d);
  }
}

}  // namespace organsim::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#endif  // include guard
