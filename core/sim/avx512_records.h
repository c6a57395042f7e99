#pragma once
// The AVX-512 kernels' point records and their in-register transposes, per
// lane width (cpu_kernel_avx512.cpp). Neighbours are read with plain loads
// of their records and transposed in registers, because a hardware gather
// of 16 lanes costs several times more here.
//
// Layouts (Records<Real>):
//   float:  one 32-byte record per point, (x, y, z, w, dx, dy, dz, 0):
//           a spring's neighbour is one load;
//   double: positions (x, y, z, w) and increments (dx, dy, dz, 0) in two
//           arrays of 32-byte quads: the tet pass reads positions only,
//           half the bytes (the two measured the same within noise for
//           springs at liver size).
// w is the nodal volume term's scaled pressure, 0 without it. The
// displacement records of the shear element have the same layouts; their
// increment's 4th value carries the smoothed stress's P_22. Force arrays
// are (x, y, z, 0) per point in both widths.
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "core/sim/avx512_lanes.h"

namespace organsim::avx512 {

// ---- float x 16 ----------------------------------------------------------------

// All eight floats of 16 points' 32-byte records (a[j] holds value j of
// every lane): eight 512-bit registers of two records each, transposed in
// registers. Register i holds records (q_i, q_{i+4}) for i < 4 and
// (q_{i+4}, q_{i+8}) above, so the shuffles below leave lanes in q order.
// Outputs a caller does not use cost nothing (the compiler drops them).
template <int Scale>
[[gnu::always_inline]] inline void gather8(const float* rec, const int32_t* q, __m512 (&a)[8]) {
  auto pair = [&](int i, int j) {
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(rec + Scale * static_cast<ptrdiff_t>(q[i]))),
                               _mm256_load_ps(rec + Scale * static_cast<ptrdiff_t>(q[j])), 1);
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
    a[j] = _mm512_shuffle_f32x4(s0[j], s1[j], _MM_SHUFFLE(2, 0, 2, 0));
    a[j + 4] = _mm512_shuffle_f32x4(s0[j], s1[j], _MM_SHUFFLE(3, 1, 3, 1));
  }
}

// The inverse of gather8 for 16 consecutive points: writes the 8-float
// records of points p0.. from a[j] (value j of every lane). Per half of the
// values a 4 x 4 transpose in each 128-bit quarter, then each register of
// two records is paired from the two halves and stored as two 32-byte rows.
[[gnu::always_inline]] inline void store8(float* out, const __m512 (&a)[8]) {
  __m512 r[2][4];  // r[h][i], quarter k: values 4h..4h+3 of point 4k + i
  for (int h = 0; h < 2; ++h) {
    const __m512 t0 = _mm512_unpacklo_ps(a[4 * h], a[4 * h + 1]), t1 = _mm512_unpackhi_ps(a[4 * h], a[4 * h + 1]);
    const __m512 t2 = _mm512_unpacklo_ps(a[4 * h + 2], a[4 * h + 3]), t3 = _mm512_unpackhi_ps(a[4 * h + 2], a[4 * h + 3]);
    r[h][0] = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
    r[h][1] = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
    r[h][2] = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
    r[h][3] = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
  }
  // Quarters (r0.k, r1.k, r0.k+1, r1.k+1): the records of points 4k + i and 4(k + 1) + i.
  const __m512i lo = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 4, 5, 6, 7, 20, 21, 22, 23);
  const __m512i hi = _mm512_add_epi32(lo, _mm512_set1_epi32(8));
  for (int i = 0; i < 4; ++i) {
    const __m512 p01 = _mm512_permutex2var_ps(r[0][i], lo, r[1][i]), p23 = _mm512_permutex2var_ps(r[0][i], hi, r[1][i]);
    _mm256_store_ps(out + 8 * i, _mm512_castps512_ps256(p01));
    _mm256_store_ps(out + 8 * (4 + i), _mm512_extractf32x8_ps(p01, 1));
    _mm256_store_ps(out + 8 * (8 + i), _mm512_castps512_ps256(p23));
    _mm256_store_ps(out + 8 * (12 + i), _mm512_extractf32x8_ps(p23, 1));
  }
}

// Neighbour positions and the records' 4th float (tets): 16-byte loads, four
// per register, and a 4 x 4 transpose inside each 128-bit quarter.
template <int Scale>
[[gnu::always_inline]] inline void gather4(const float* rec, const int32_t* q, __m512& x, __m512& y, __m512& z, __m512& w) {
  // 64-bit before the doubling, so that it folds into the load's addressing
  // (in 32 bits the compiler keeps the wrap-around: an add and a sign
  // extension per point, a sixth of the tet loop's instructions).
  auto at = [&](int l) { return rec + Scale * static_cast<ptrdiff_t>(q[l]); };
  auto quad = [&](int i) {
    __m512 r = _mm512_castps128_ps512(_mm_load_ps(at(i)));
    r = _mm512_insertf32x4(r, _mm_load_ps(at(i + 4)), 1);
    r = _mm512_insertf32x4(r, _mm_load_ps(at(i + 8)), 2);
    return _mm512_insertf32x4(r, _mm_load_ps(at(i + 12)), 3);
  };
  const __m512 r0 = quad(0), r1 = quad(1), r2 = quad(2), r3 = quad(3);
  const __m512 t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const __m512 t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  x = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  y = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  z = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  w = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
// Positions only (the unused shuffle for w is dropped by the compiler).
template <int Scale>
[[gnu::always_inline]] inline void gather3(const float* rec, const int32_t* q, __m512& x, __m512& y, __m512& z) {
  __m512 unused;
  gather4<Scale>(rec, q, x, y, z, unused);
}

// Writes the records of 16 consecutive points p0.. (the inverse transpose):
// each output register holds two consecutive records.
[[gnu::always_inline]] inline void store_records(float* rec, const __m512& x, const __m512& y, const __m512& z, const __m512& dx, const __m512& dy, const __m512& dz) {
  // Quarter k of s holds lane k of points (p, p+2, p+4, p+6) in the order
  // position, increment, position of the next point, its increment.
  const __m512i lo = _mm512_setr_epi32(0, 2, 4, 6, 16, 18, 20, 22, 1, 3, 5, 7, 17, 19, 21, 23);
  const __m512i hi = _mm512_add_epi32(lo, _mm512_set1_epi32(8));
  const __m512 zero = _mm512_setzero_ps();
  for (int half = 0; half < 2; ++half) {
    const __m512i idx = half ? hi : lo;
    const __m512 sx = _mm512_permutex2var_ps(x, idx, dx), sy = _mm512_permutex2var_ps(y, idx, dy);
    const __m512 sz = _mm512_permutex2var_ps(z, idx, dz);
    const __m512 u0 = _mm512_unpacklo_ps(sx, sy), u1 = _mm512_unpackhi_ps(sx, sy);
    const __m512 u2 = _mm512_unpacklo_ps(sz, zero), u3 = _mm512_unpackhi_ps(sz, zero);
    float* out = rec + 64 * half;
    _mm512_store_ps(out + 0, _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)));
    _mm512_store_ps(out + 16, _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)));
    _mm512_store_ps(out + 32, _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)));
    _mm512_store_ps(out + 48, _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2)));
  }
}

// Adds lane l of (x, y, z) to the 16-byte force of point q[l]. The 16
// points of a batch are distinct (batch_tets()), so all 16 forces are loaded
// before any is stored; padding lanes all point at npad, whose force stays
// zero (they add zero).
template <int Quarter>
[[gnu::always_inline]] inline void add_quarter(const float* force, const int32_t* q, const __m512 (&r)[4], __m128 (&sum)[16]) {
  for (int i = 0; i < 4; ++i)
    sum[4 * Quarter + i] = _mm_add_ps(_mm_load_ps(force + q[4 * Quarter + i]),
                                      _mm512_extractf32x4_ps(r[i], Quarter));
}
[[gnu::always_inline]] inline void scatter_add(float* force, const int32_t* q, __m512 x, __m512 y, __m512 z) {
  // The inverse of gather3: quarter k of r[i] is (x, y, z, 0) of lane 4k + i.
  const __m512 zero = _mm512_setzero_ps();
  const __m512 u0 = _mm512_unpacklo_ps(x, y), u1 = _mm512_unpackhi_ps(x, y);
  const __m512 u2 = _mm512_unpacklo_ps(z, zero), u3 = _mm512_unpackhi_ps(z, zero);
  const __m512 r[4] = {_mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)),
                  _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2))};
  __m128 sum[16];
  add_quarter<0>(force, q, r, sum);
  add_quarter<1>(force, q, r, sum);
  add_quarter<2>(force, q, r, sum);
  add_quarter<3>(force, q, r, sum);
  for (int l = 0; l < 16; ++l) _mm_store_ps(force + q[l], sum[l]);
}

// Adds the 16-byte forces of 16 consecutive points to (fx, fy, fz) and clears them.
[[gnu::always_inline]] inline void take_forces(float* force, __m512& fx, __m512& fy, __m512& fz) {
  const __m512 l0 = _mm512_load_ps(force), l1 = _mm512_load_ps(force + 16), l2 = _mm512_load_ps(force + 32),
          l3 = _mm512_load_ps(force + 48);
  const __m512i ix = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 0, 4, 8, 12, 16, 20, 24, 28);
  auto component = [&](int k) {
    const __m512i idx = _mm512_add_epi32(ix, _mm512_set1_epi32(k));
    return _mm512_shuffle_f32x4(_mm512_permutex2var_ps(l0, idx, l1), _mm512_permutex2var_ps(l2, idx, l3),
                                _MM_SHUFFLE(1, 0, 1, 0));
  };
  fx = _mm512_add_ps(fx, component(0));
  fy = _mm512_add_ps(fy, component(1));
  fz = _mm512_add_ps(fz, component(2));
  for (int i = 0; i < 4; ++i) _mm512_store_ps(force + 16 * i, _mm512_setzero_ps());
}


// ---- double x 8 ----------------------------------------------------------------

// (x, y, z, w) of 8 points from their 32-byte quads at base + Scale q[i]:
// four 512-bit registers of two quads each, transposed in registers.
// Register i holds quads (q_a, q_b) with (a, b) = (0, 2), (1, 3), (4, 6),
// (5, 7), so that the shuffles below leave lanes in q order.
template <int Scale>
[[gnu::always_inline]] inline void gather4(const double* base, const int32_t* q, __m512d& x, __m512d& y, __m512d& z, __m512d& w) {
  auto pair = [&](int a, int b) {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(base + Scale * q[a])),
                              _mm256_load_pd(base + Scale * q[b]), 1);
  };
  const __m512d r0 = pair(0, 2), r1 = pair(1, 3), r2 = pair(4, 6), r3 = pair(5, 7);
  // t0 = (x0 x1 | z0 z1 | x2 x3 | z2 z3), t1 = (y0 y1 | w0 w1 | y2 y3 | w2 w3), t2, t3 likewise for 4..7.
  const __m512d t0 = _mm512_unpacklo_pd(r0, r1), t1 = _mm512_unpackhi_pd(r0, r1);
  const __m512d t2 = _mm512_unpacklo_pd(r2, r3), t3 = _mm512_unpackhi_pd(r2, r3);
  x = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(2, 0, 2, 0));
  y = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(2, 0, 2, 0));
  z = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(3, 1, 3, 1));
  w = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(3, 1, 3, 1));
}
// (x, y, z) only (the unused shuffle for w is dropped by the compiler).
template <int Scale>
[[gnu::always_inline]] inline void gather3(const double* base, const int32_t* q, __m512d& x, __m512d& y, __m512d& z) {
  __m512d unused;
  gather4<Scale>(base, q, x, y, z, unused);
}

// An 8 x 8 transpose in three rounds: a[j] lane i = r[i] lane j.
[[gnu::always_inline]] inline void transpose8(const __m512d (&r)[8], __m512d (&a)[8]) {
  // t[2i] = (r_2i[0] r_2i+1[0] | r_2i[2] r_2i+1[2] | ...), t[2i+1] the odd values.
  __m512d t[8];
  for (int i = 0; i < 4; ++i) {
    t[2 * i] = _mm512_unpacklo_pd(r[2 * i], r[2 * i + 1]);
    t[2 * i + 1] = _mm512_unpackhi_pd(r[2 * i], r[2 * i + 1]);
  }
  // u[4h + j]: values (j, j + 4) of points 4h..4h+3, in 128-bit pairs of points.
  __m512d u[8];
  for (int h = 0; h < 2; ++h)
    for (int e = 0; e < 2; ++e) {
      const __m512d lo = t[4 * h + e], hi = t[4 * h + 2 + e];
      u[4 * h + e] = _mm512_shuffle_f64x2(lo, hi, _MM_SHUFFLE(2, 0, 2, 0));      // values e, e + 4
      u[4 * h + 2 + e] = _mm512_shuffle_f64x2(lo, hi, _MM_SHUFFLE(3, 1, 3, 1));  // values e + 2, e + 6
    }
  for (int j = 0; j < 4; ++j) {
    a[j] = _mm512_shuffle_f64x2(u[j], u[4 + j], _MM_SHUFFLE(2, 0, 2, 0));
    a[j + 4] = _mm512_shuffle_f64x2(u[j], u[4 + j], _MM_SHUFFLE(3, 1, 3, 1));
  }
}

// All eight doubles of 8 points' 64-byte records (a[j] holds value j of
// every lane): one load per point and a transpose.
template <int Scale>
[[gnu::always_inline]] inline void gather8(const double* base, const int32_t* q, __m512d (&a)[8]) {
  __m512d r[8];
  for (int i = 0; i < 8; ++i) r[i] = _mm512_load_pd(base + Scale * static_cast<ptrdiff_t>(q[i]));
  transpose8(r, a);
}

// The inverse for 8 consecutive points: their records from a[j] (value j of every lane).
[[gnu::always_inline]] inline void store8(double* out, const __m512d (&a)[8]) {
  __m512d r[8];
  transpose8(a, r);
  for (int i = 0; i < 8; ++i) _mm512_store_pd(out + 8 * i, r[i]);
}

// The inverse of gather3 for 8 consecutive points: out[i] holds the quads
// (x, y, z, 0) of points 2i and 2i + 1.
[[gnu::always_inline]] inline void to_quads(const __m512d& x, const __m512d& y, const __m512d& z, __m512d (&out)[4]) {
  const __m512d zero = _mm512_setzero_pd();
  // a = (x0 y0 | x2 y2 | x4 y4 | x6 y6), b the odd points; c, d the same for (z, 0).
  const __m512d a = _mm512_unpacklo_pd(x, y), b = _mm512_unpackhi_pd(x, y);
  const __m512d c = _mm512_unpacklo_pd(z, zero), d = _mm512_unpackhi_pd(z, zero);
  // e = (x0 y0 | x2 y2 | z0 0 | z2 0), f the same for points 1 and 3; g, h for 4..7.
  const __m512d e = _mm512_shuffle_f64x2(a, c, _MM_SHUFFLE(1, 0, 1, 0)), f = _mm512_shuffle_f64x2(b, d, _MM_SHUFFLE(1, 0, 1, 0));
  const __m512d g = _mm512_shuffle_f64x2(a, c, _MM_SHUFFLE(3, 2, 3, 2)), h = _mm512_shuffle_f64x2(b, d, _MM_SHUFFLE(3, 2, 3, 2));
  out[0] = _mm512_shuffle_f64x2(e, f, _MM_SHUFFLE(2, 0, 2, 0));
  out[1] = _mm512_shuffle_f64x2(e, f, _MM_SHUFFLE(3, 1, 3, 1));
  out[2] = _mm512_shuffle_f64x2(g, h, _MM_SHUFFLE(2, 0, 2, 0));
  out[3] = _mm512_shuffle_f64x2(g, h, _MM_SHUFFLE(3, 1, 3, 1));
}

// Writes the quads (x, y, z, 0) of 8 consecutive points from `out` on.
[[gnu::always_inline]] inline void store_quads(double* out, const __m512d& x, const __m512d& y, const __m512d& z) {
  __m512d quads[4];
  to_quads(x, y, z, quads);
  for (int i = 0; i < 4; ++i) _mm512_store_pd(out + 8 * i, quads[i]);
}

// Adds lane l of (x, y, z) to the 32-byte force of point q[l]. The 8 points
// of a batch are distinct (tet_batches.h), so all 8 forces are loaded before
// any is stored; padding lanes all point at npad, whose force stays zero.
// The quads are made per 256-bit half (4 x 4 transposes), which takes fewer
// shuffles than to_quads() and the extraction of its halves.
[[gnu::always_inline]] inline void scatter_add(double* force, const int32_t* q, __m512d x, __m512d y, __m512d z) {
  __m256d sum[8];
  // The halves up front: the extraction's index must be a constant (clang
  // insists even where the loop below is unrolled).
  const __m256d xs[2] = {_mm512_castpd512_pd256(x), _mm512_extractf64x4_pd(x, 1)};
  const __m256d ys[2] = {_mm512_castpd512_pd256(y), _mm512_extractf64x4_pd(y, 1)};
  const __m256d zs[2] = {_mm512_castpd512_pd256(z), _mm512_extractf64x4_pd(z, 1)};
  for (int h = 0; h < 2; ++h) {
    const __m256d xh = xs[h], yh = ys[h], zh = zs[h], zero = _mm256_setzero_pd();
    // a = (x0 y0 | x2 y2), b = (x1 y1 | x3 y3), c = (z0 0 | z2 0), d = (z1 0 | z3 0)
    const __m256d a = _mm256_unpacklo_pd(xh, yh), b = _mm256_unpackhi_pd(xh, yh);
    const __m256d c = _mm256_unpacklo_pd(zh, zero), d = _mm256_unpackhi_pd(zh, zero);
    const __m256d quad[4] = {_mm256_permute2f128_pd(a, c, 0x20), _mm256_permute2f128_pd(b, d, 0x20),
                             _mm256_permute2f128_pd(a, c, 0x31), _mm256_permute2f128_pd(b, d, 0x31)};
    for (int i = 0; i < 4; ++i) sum[4 * h + i] = _mm256_add_pd(_mm256_load_pd(force + q[4 * h + i]), quad[i]);
  }
  for (int l = 0; l < 8; ++l) _mm256_store_pd(force + q[l], sum[l]);
}

// Adds the 32-byte forces of 8 consecutive points to (fx, fy, fz) and clears them.
[[gnu::always_inline]] inline void take_forces(double* force, __m512d& fx, __m512d& fy, __m512d& fz) {
  const __m512d l0 = _mm512_load_pd(force), l1 = _mm512_load_pd(force + 8), l2 = _mm512_load_pd(force + 16),
          l3 = _mm512_load_pd(force + 24);
  // From two registers of quads (points i..i+3): (x_i..x_i+3, y_i..y_i+3) and (z_i..z_i+3, -).
  const __m512i xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
  const __m512i z_ = _mm512_setr_epi64(2, 6, 10, 14, 2, 6, 10, 14);
  const __m512d xy0 = _mm512_permutex2var_pd(l0, xy, l1), xy1 = _mm512_permutex2var_pd(l2, xy, l3);
  const __m512d z0 = _mm512_permutex2var_pd(l0, z_, l1), z1 = _mm512_permutex2var_pd(l2, z_, l3);
  fx = _mm512_add_pd(fx, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(1, 0, 1, 0)));
  fy = _mm512_add_pd(fy, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(3, 2, 3, 2)));
  fz = _mm512_add_pd(fz, _mm512_shuffle_f64x2(z0, z1, _MM_SHUFFLE(1, 0, 1, 0)));
  for (int i = 0; i < 4; ++i) _mm512_store_pd(force + 8 * i, _mm512_setzero_pd());
}

// ---- One interface for both widths ------------------------------------------

template <class Real>
struct Records;
template <>
struct Records<float> {
  static constexpr int32_t kRecord = 8;  // floats per point in the record array
  static constexpr bool kSplit = false;  // increments inside the records
};
template <>
struct Records<double> {
  static constexpr int32_t kRecord = 4;
  static constexpr bool kSplit = true;  // increments in their own array
};

// Position and increment of the neighbours q (pre-scaled offsets; the
// records at rec + Scale q, increments at inc + Scale q when split).
// dw is the increment's 4th value (float: the record's last; double: w of
// the increment quad), which the smoothed shear pass uses for P_22.
template <int Scale>
[[gnu::always_inline]] inline void gather_xd(const float* rec, const float*, const int32_t* q, V<float> (&x)[3],
                                             V<float> (&d)[3], V<float>& dw) {
  __m512 a[8];
  gather8<Scale>(rec, q, a);
  for (int k = 0; k < 3; ++k) x[k].r = a[k], d[k].r = a[4 + k];
  dw.r = a[7];
}
template <int Scale>
[[gnu::always_inline]] inline void gather_xd(const double* rec, const double* inc, const int32_t* q,
                                             V<double> (&x)[3], V<double> (&d)[3], V<double>& dw) {
  gather3<Scale>(rec, q, x[0].r, x[1].r, x[2].r);
  gather4<Scale>(inc, q, d[0].r, d[1].r, d[2].r, dw.r);
}
template <int Scale, class Real>
[[gnu::always_inline]] inline void gather_xd(const Real* rec, const Real* inc, const int32_t* q, V<Real> (&x)[3],
                                             V<Real> (&d)[3]) {
  V<Real> unused;
  gather_xd<Scale>(rec, inc, q, x, d, unused);
}
// Eight values per point from 8-value records (float 32 bytes, double 64),
// and the records of the points p0.. from eight values per lane.
template <int Scale, class Real>
[[gnu::always_inline]] inline void gather_8(const Real* base, const int32_t* q, V<Real> (&a)[8]) {
  decltype(a[0].r) r[8];
  gather8<Scale>(base, q, r);
  for (int j = 0; j < 8; ++j) a[j].r = r[j];
}
template <class Real>
[[gnu::always_inline]] inline void store_8(Real* out, const V<Real> (&a)[8]) {
  decltype(a[0].r) r[8];
  for (int j = 0; j < 8; ++j) r[j] = a[j].r;
  store8(out, r);
}
// Position only, and position with w.
template <int Scale, class Real>
[[gnu::always_inline]] inline void gather_x(const Real* rec, const int32_t* q, V<Real> (&x)[3]) {
  gather3<Scale>(rec, q, x[0].r, x[1].r, x[2].r);
}
template <int Scale, class Real>
[[gnu::always_inline]] inline void gather_xw(const Real* rec, const int32_t* q, V<Real> (&x)[3], V<Real>& w) {
  gather4<Scale>(rec, q, x[0].r, x[1].r, x[2].r, w.r);
}

// The records of the points p0.. (one register of lanes).
[[gnu::always_inline]] inline void store_records(float* rec, float*, int32_t p0, const V<float> (&x)[3],
                                                 const V<float> (&d)[3]) {
  store_records(rec + 8 * static_cast<size_t>(p0), x[0].r, x[1].r, x[2].r, d[0].r, d[1].r, d[2].r);
}
[[gnu::always_inline]] inline void store_records(double* rec, double* inc, int32_t p0, const V<double> (&x)[3],
                                                 const V<double> (&d)[3]) {
  store_quads(rec + 4 * static_cast<size_t>(p0), x[0].r, x[1].r, x[2].r);
  store_quads(inc + 4 * static_cast<size_t>(p0), d[0].r, d[1].r, d[2].r);
}
// The positions only (split layouts), the whole records otherwise.
[[gnu::always_inline]] inline void store_positions(float* rec, int32_t p0, const V<float> (&x)[3],
                                                   const V<float> (&d)[3]) {
  store_records(rec, nullptr, p0, x, d);
}
[[gnu::always_inline]] inline void store_positions(double* rec, int32_t p0, const V<double> (&x)[3],
                                                   const V<double> (&)[3]) {
  store_quads(rec + 4 * static_cast<size_t>(p0), x[0].r, x[1].r, x[2].r);
}

// Adds lane l of f to the force of point q[l] (q pre-scaled by 4; the
// lanes' points distinct), and takes the forces of the points p0.. into f,
// clearing them.
template <class Real>
[[gnu::always_inline]] inline void scatter_add(Real* force, const int32_t* q, const V<Real> (&f)[3]) {
  scatter_add(force, q, f[0].r, f[1].r, f[2].r);
}
template <class Real>
[[gnu::always_inline]] inline void take_forces(Real* force, V<Real> (&f)[3]) {
  take_forces(force, f[0].r, f[1].r, f[2].r);
}

}  // namespace organsim::avx512
