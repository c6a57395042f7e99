#pragma once
// One 512-bit register of Real lanes for the AVX-512 kernels
// (cpu_kernel_avx512.cpp): float x 16 or double x 8 behind one set of
// operators, so that the kernels' arithmetic is written once for both
// precisions. What differs by width is here and only here: the arithmetic
// wrappers below, and the record layouts and their in-register transposes
// (avx512_records.h). Included only where the compiler targets AVX-512.
#include <immintrin.h>

#include <cstdint>

namespace organsim::avx512 {

template <class Real>
struct Lanes;

template <>
struct Lanes<float> {
  using Reg = __m512;
  using Mask = __mmask16;
  static constexpr int32_t kLanes = 16;
};
template <>
struct Lanes<double> {
  using Reg = __m512d;
  using Mask = __mmask8;
  static constexpr int32_t kLanes = 8;
};

// A register of Real lanes.
template <class Real>
struct V {
  typename Lanes<Real>::Reg r;
};
template <class Real>
using MaskOf = typename Lanes<Real>::Mask;

#define ORGANSIM_V_OPS(Real, sfx)                                                                              \
  [[gnu::always_inline]] inline V<Real> operator+(V<Real> a, V<Real> b) { return {_mm512_add_##sfx(a.r, b.r)}; } \
  [[gnu::always_inline]] inline V<Real> operator-(V<Real> a, V<Real> b) { return {_mm512_sub_##sfx(a.r, b.r)}; } \
  [[gnu::always_inline]] inline V<Real> operator*(V<Real> a, V<Real> b) { return {_mm512_mul_##sfx(a.r, b.r)}; } \
  [[gnu::always_inline]] inline V<Real> operator/(V<Real> a, V<Real> b) { return {_mm512_div_##sfx(a.r, b.r)}; } \
  [[gnu::always_inline]] inline V<Real>& operator+=(V<Real>& a, V<Real> b) { return a = a + b; }              \
  /* a b + c, a b - c */                                                                                       \
  [[gnu::always_inline]] inline V<Real> fmadd(V<Real> a, V<Real> b, V<Real> c) {                             \
    return {_mm512_fmadd_##sfx(a.r, b.r, c.r)};                                                                \
  }                                                                                                            \
  [[gnu::always_inline]] inline V<Real> fmsub(V<Real> a, V<Real> b, V<Real> c) {                             \
    return {_mm512_fmsub_##sfx(a.r, b.r, c.r)};                                                                \
  }                                                                                                            \
  [[gnu::always_inline]] inline V<Real> fnmadd(V<Real> a, V<Real> b, V<Real> c) {                            \
    return {_mm512_fnmadd_##sfx(a.r, b.r, c.r)};                                                               \
  }                                                                                                            \
  [[gnu::always_inline]] inline V<Real> load(const Real* p) { return {_mm512_load_##sfx(p)}; }                \
  [[gnu::always_inline]] inline void store(Real* p, V<Real> a) { _mm512_store_##sfx(p, a.r); }               \
  [[gnu::always_inline]] inline V<Real> splat(Real a) { return {_mm512_set1_##sfx(a)}; }                      \
  [[gnu::always_inline]] inline V<Real> zero(Real) { return {_mm512_setzero_##sfx()}; }                       \
  [[gnu::always_inline]] inline V<Real> abs(V<Real> a) { return {_mm512_abs_##sfx(a.r)}; }                    \
  [[gnu::always_inline]] inline V<Real> max(V<Real> a, V<Real> b) { return {_mm512_max_##sfx(a.r, b.r)}; }    \
  [[gnu::always_inline]] inline MaskOf<Real> operator<(V<Real> a, V<Real> b) {                                \
    return _mm512_cmp_##sfx##_mask(a.r, b.r, _CMP_LT_OQ);                                                      \
  }                                                                                                            \
  [[gnu::always_inline]] inline MaskOf<Real> operator>(V<Real> a, V<Real> b) {                                \
    return _mm512_cmp_##sfx##_mask(a.r, b.r, _CMP_GT_OQ);                                                      \
  }                                                                                                            \
  [[gnu::always_inline]] inline MaskOf<Real> operator>=(V<Real> a, V<Real> b) {                               \
    return _mm512_cmp_##sfx##_mask(a.r, b.r, _CMP_GE_OQ);                                                      \
  }                                                                                                            \
  /* Lanes of a where m is set, b elsewhere; zero where m is clear. */                                         \
  [[gnu::always_inline]] inline V<Real> select(MaskOf<Real> m, V<Real> a, V<Real> b) {                        \
    return {_mm512_mask_mov_##sfx(b.r, m, a.r)};                                                               \
  }                                                                                                            \
  [[gnu::always_inline]] inline V<Real> keep(MaskOf<Real> m, V<Real> a) { return {_mm512_maskz_mov_##sfx(m, a.r)}; }

ORGANSIM_V_OPS(float, ps)
ORGANSIM_V_OPS(double, pd)
#undef ORGANSIM_V_OPS

template <class Real>
[[gnu::always_inline]] inline V<Real> zero() {
  return zero(Real(0));
}

// 1/|l| for |l|^2 = len2 > 0, 0 otherwise (padding, coincident ends): the
// 14-bit estimate and Newton steps (one for float, two for double: 14 -> 28
// -> 56 bits, within a few ulps; a division and a square root cost several
// times more here). The rest lengths are computed by this same function, so
// the rest state is force-free.
[[gnu::always_inline]] inline V<float> inv_length(V<float> len2) {
  const V<float> y{_mm512_maskz_rsqrt14_ps(len2 > zero<float>(), len2.r)};
  return y * fnmadd(splat(0.5f) * len2 * y, y, splat(1.5f));  // y (1.5 - x y^2 / 2)
}
[[gnu::always_inline]] inline V<double> inv_length(V<double> len2) {
  V<double> y{_mm512_maskz_rsqrt14_pd(len2 > zero<double>(), len2.r)};
  const V<double> half_x = splat(0.5) * len2;
  y = y * fnmadd(half_x * y, y, splat(1.5));
  return y * fnmadd(half_x * y, y, splat(1.5));
}

// Lanes of 32-bit indices from an int32 array: whether each is >= 0.
[[gnu::always_inline]] inline __mmask16 nonnegative(const int32_t* a, float) {
  return _mm512_cmp_epi32_mask(_mm512_loadu_si512(a), _mm512_setzero_si512(), _MM_CMPINT_NLT);
}
[[gnu::always_inline]] inline __mmask8 nonnegative(const int32_t* a, double) {
  const __m512i v = _mm512_castsi256_si512(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(a)));
  return static_cast<__mmask8>(_mm512_mask_cmp_epi32_mask(0xff, v, _mm512_setzero_si512(), _MM_CMPINT_NLT));
}

// Hardware gather of base[idx[l]] for the lanes' int32 indices: for the
// few per-point sums that read one value per slot.
[[gnu::always_inline]] inline V<float> gather_at(const float* base, const int32_t* idx) {
  return {_mm512_i32gather_ps(_mm512_load_si512(idx), base, 4)};
}
[[gnu::always_inline]] inline V<double> gather_at(const double* base, const int32_t* idx) {
  return {_mm512_i32gather_pd(_mm256_load_si256(reinterpret_cast<const __m256i*>(idx)), base, 8)};
}

}  // namespace organsim::avx512
