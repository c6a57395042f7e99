#include "core/sim/cpu_kernel_avx512_double.h"

#include <algorithm>

#include "core/sim/tet_batches.h"
#include "core/util/aligned_vector.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__)
#define ORGANSIM_HAVE_AVX512 1
// GCC 12's AVX-512 intrinsics fill unused operands with _mm512_undefined_pd(),
// which -Wuninitialized reports at every inlined use (a known false positive).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#include <omp.h>
#endif

namespace organsim {

namespace {

constexpr int32_t kLanes = 8;  // doubles per 512-bit register
// Fixed tet slices, each summed into its own force array and added per
// point in order (as in the float kernel): results do not depend on the
// thread count.
constexpr int kSlices = 2;
// Doubles per point in the record array: 4 keeps positions (x, y, z, 0) and
// increments (dx, dy, dz, 0) in two arrays ("split"); 8 keeps one 64-byte
// record (x, y, z, 0, dx, dy, dz, 0) per point. Both are implemented (the
// index scaling and the record stores differ); the two measured the same
// within noise at liver size (AMD EPYC, Zen 4), and split is kept because
// the tet pass reads positions only, half the bytes.
constexpr int32_t kRecord = 4;

}  // namespace

struct Avx512DoubleKernel::Data {
  int32_t npoint = 0, npad = 0, chunk = 0, nchunk = 0, groups = 0;  // groups of 8 per chunk
  ElementTerm volume = ElementTerm::None;
  bool gravity = false;
  AlignedVector<double> rest[3], mass, inv_mass;  // (npad)
  AlignedVector<double> u[2][3], d[2][3];         // state, double-buffered (npad)
  // Records, double-buffered (kRecord (npad + 8)): positions (x, y, z, q),
  // q the nodal term's scaled pressure (node_k), 0 without it, and with
  // kRecord = 8 also the increments; with kRecord = 4 the increments are in
  // `inc` (4 (npad + 8)). The entry at npad stays zero: padding tets point at it.
  AlignedVector<double> rec[2], inc[2];
  int cur = 0;                                    // which buffer holds step t
  std::vector<int32_t> spring_offset;             // first entry of each chunk (nchunk)
  std::vector<int32_t> spring_width;              // slots per group of 8 (nchunk x groups)
  // Indices pre-scaled to double offsets: kRecord q into the records, 4 q
  // into the increments and force slices.
  AlignedVector<int32_t> spring_other;            // kRecord x other end per entry; padding points at itself
  AlignedVector<double> spring_rest, spring_k, spring_d;
  AlignedVector<int32_t> tet_v[4];                // 4 x vertex per batch lane; padding lanes: 4 npad
  AlignedVector<double> tet_k36, tet_det_rest;    // per tet: k_v / 36 and 6 V_r as the kernel computes it; else empty
  // Nodal term, as in the float kernel: q = node_k (S - node_rest) per
  // point, S the sum of 6 V_t over its tets, node_k = -k_a / 576, node_rest
  // = S at rest as the kernel computes it (npad); else empty.
  AlignedVector<double> node_k, node_rest;
  int32_t slice_begin[kSlices + 1] = {};          // batches of each slice
  // (x, y, z, S) per point, zero between steps (4 (npad + 8)): the tet
  // forces, and with the nodal term the slice's part of S.
  AlignedVector<double> tet_force[kSlices];
};

Avx512DoubleKernel::Avx512DoubleKernel() : data_(std::make_unique<Data>()) {}
Avx512DoubleKernel::~Avx512DoubleKernel() = default;

int32_t Avx512DoubleKernel::nchunk() const { return data_->nchunk; }

size_t Avx512DoubleKernel::bytes() const {
  const Data& D = *data_;
  const size_t n = static_cast<size_t>(D.npad);
  return n * sizeof(double) * (3 + 2 + 12 + 2 * 8 + 4 * kSlices) +
         D.spring_other.size() * (sizeof(int32_t) + 3 * sizeof(double)) +
         D.tet_v[0].size() * 4 * sizeof(int32_t) + (D.tet_k36.size() + D.tet_det_rest.size()) * sizeof(double) +
         (D.node_k.size() + D.node_rest.size()) * sizeof(double);
}

void Avx512DoubleKernel::get_point(int32_t p, double u[3], double d[3]) const {
  const Data& D = *data_;
  for (int k = 0; k < 3; ++k) {
    u[k] = D.u[D.cur][k][p];
    d[k] = D.d[D.cur][k][p];
  }
}

#if ORGANSIM_HAVE_AVX512

namespace {

using V = __m512d;

double* positions(Avx512DoubleKernel::Data& D, int b) { return D.rec[b].data(); }
double* increments(Avx512DoubleKernel::Data& D, int b) {
  return kRecord == 8 ? D.rec[b].data() + 4 : D.inc[b].data();
}

// (x, y, z, w) of 8 points from their 32-byte quads at base + Scale q[i]:
// four 512-bit registers of two quads each, transposed in registers.
// Register i holds quads (q_a, q_b) with (a, b) = (0, 2), (1, 3), (4, 6),
// (5, 7), so that the shuffles below leave lanes in q order.
template <int Scale>
[[gnu::always_inline]] inline void gather4(const double* base, const int32_t* q, V& x, V& y, V& z, V& w) {
  auto pair = [&](int a, int b) {
    return _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(base + Scale * q[a])),
                              _mm256_load_pd(base + Scale * q[b]), 1);
  };
  const V r0 = pair(0, 2), r1 = pair(1, 3), r2 = pair(4, 6), r3 = pair(5, 7);
  // t0 = (x0 x1 | z0 z1 | x2 x3 | z2 z3), t1 = (y0 y1 | w0 w1 | y2 y3 | w2 w3), t2, t3 likewise for 4..7.
  const V t0 = _mm512_unpacklo_pd(r0, r1), t1 = _mm512_unpackhi_pd(r0, r1);
  const V t2 = _mm512_unpacklo_pd(r2, r3), t3 = _mm512_unpackhi_pd(r2, r3);
  x = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(2, 0, 2, 0));
  y = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(2, 0, 2, 0));
  z = _mm512_shuffle_f64x2(t0, t2, _MM_SHUFFLE(3, 1, 3, 1));
  w = _mm512_shuffle_f64x2(t1, t3, _MM_SHUFFLE(3, 1, 3, 1));
}
// (x, y, z) only (the unused shuffle for w is dropped by the compiler).
template <int Scale>
[[gnu::always_inline]] inline void gather3(const double* base, const int32_t* q, V& x, V& y, V& z) {
  V unused;
  gather4<Scale>(base, q, x, y, z, unused);
}

// The inverse of gather3 for 8 consecutive points: out[i] holds the quads
// (x, y, z, 0) of points 2i and 2i + 1.
[[gnu::always_inline]] inline void to_quads(const V& x, const V& y, const V& z, V (&out)[4]) {
  const V zero = _mm512_setzero_pd();
  // a = (x0 y0 | x2 y2 | x4 y4 | x6 y6), b the odd points; c, d the same for (z, 0).
  const V a = _mm512_unpacklo_pd(x, y), b = _mm512_unpackhi_pd(x, y);
  const V c = _mm512_unpacklo_pd(z, zero), d = _mm512_unpackhi_pd(z, zero);
  // e = (x0 y0 | x2 y2 | z0 0 | z2 0), f the same for points 1 and 3; g, h for 4..7.
  const V e = _mm512_shuffle_f64x2(a, c, _MM_SHUFFLE(1, 0, 1, 0)), f = _mm512_shuffle_f64x2(b, d, _MM_SHUFFLE(1, 0, 1, 0));
  const V g = _mm512_shuffle_f64x2(a, c, _MM_SHUFFLE(3, 2, 3, 2)), h = _mm512_shuffle_f64x2(b, d, _MM_SHUFFLE(3, 2, 3, 2));
  out[0] = _mm512_shuffle_f64x2(e, f, _MM_SHUFFLE(2, 0, 2, 0));
  out[1] = _mm512_shuffle_f64x2(e, f, _MM_SHUFFLE(3, 1, 3, 1));
  out[2] = _mm512_shuffle_f64x2(g, h, _MM_SHUFFLE(2, 0, 2, 0));
  out[3] = _mm512_shuffle_f64x2(g, h, _MM_SHUFFLE(3, 1, 3, 1));
}

// Writes the records of 8 consecutive points p0.. for buffer b.
[[gnu::always_inline]] inline void store_records(double* rec, double* inc, int32_t p0, const V& x, const V& y,
                                                 const V& z, const V& dx, const V& dy, const V& dz) {
  V P[4], I[4];
  to_quads(x, y, z, P);
  to_quads(dx, dy, dz, I);
  for (int i = 0; i < 4; ++i) {
    if constexpr (kRecord == 8) {
      double* out = rec + 8 * static_cast<size_t>(p0) + 16 * i;
      _mm512_store_pd(out, _mm512_shuffle_f64x2(P[i], I[i], _MM_SHUFFLE(1, 0, 1, 0)));
      _mm512_store_pd(out + 8, _mm512_shuffle_f64x2(P[i], I[i], _MM_SHUFFLE(3, 2, 3, 2)));
    } else {
      _mm512_store_pd(rec + 4 * static_cast<size_t>(p0) + 8 * i, P[i]);
      _mm512_store_pd(inc + 4 * static_cast<size_t>(p0) + 8 * i, I[i]);
    }
  }
}

// Adds lane l of (x, y, z) to the 32-byte force of point q[l]. The 8 points
// of a batch are distinct (tet_batches.h), so all 8 forces are loaded before
// any is stored; padding lanes all point at npad, whose force stays zero.
// The quads are made per 256-bit half (4 x 4 transposes), which takes fewer
// shuffles than to_quads() and the extraction of its halves.
[[gnu::always_inline]] inline void scatter_add(double* force, const int32_t* q, V x, V y, V z) {
  __m256d sum[kLanes];
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
  for (int l = 0; l < kLanes; ++l) _mm256_store_pd(force + q[l], sum[l]);
}

// Adds the 32-byte forces of 8 consecutive points to (fx, fy, fz) and clears them.
[[gnu::always_inline]] inline void take_forces(double* force, V& fx, V& fy, V& fz) {
  const V l0 = _mm512_load_pd(force), l1 = _mm512_load_pd(force + 8), l2 = _mm512_load_pd(force + 16),
          l3 = _mm512_load_pd(force + 24);
  // From two registers of quads (points i..i+3): (x_i..x_i+3, y_i..y_i+3) and (z_i..z_i+3, -).
  const __m512i xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13);
  const __m512i z_ = _mm512_setr_epi64(2, 6, 10, 14, 2, 6, 10, 14);
  const V xy0 = _mm512_permutex2var_pd(l0, xy, l1), xy1 = _mm512_permutex2var_pd(l2, xy, l3);
  const V z0 = _mm512_permutex2var_pd(l0, z_, l1), z1 = _mm512_permutex2var_pd(l2, z_, l3);
  fx = _mm512_add_pd(fx, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(1, 0, 1, 0)));
  fy = _mm512_add_pd(fy, _mm512_shuffle_f64x2(xy0, xy1, _MM_SHUFFLE(3, 2, 3, 2)));
  fz = _mm512_add_pd(fz, _mm512_shuffle_f64x2(z0, z1, _MM_SHUFFLE(1, 0, 1, 0)));
  for (int i = 0; i < 4; ++i) _mm512_store_pd(force + 8 * i, _mm512_setzero_pd());
}

// 1/|l| for |l|^2 = len2 > 0, 0 otherwise (padding, coincident ends): the
// 14-bit estimate and two Newton steps (14 -> 28 -> 56 bits, so within a
// few ulps; a division and a square root cost several times more here).
// The rest lengths are computed by this same function, so the rest state is
// force-free.
inline V inv_length(V len2) {
  const __mmask8 nonzero = _mm512_cmp_pd_mask(len2, _mm512_setzero_pd(), _CMP_GT_OQ);
  V y = _mm512_maskz_rsqrt14_pd(nonzero, len2);
  const V half_x = _mm512_mul_pd(_mm512_set1_pd(0.5), len2);
  // y (1.5 - x y^2 / 2), twice
  y = _mm512_mul_pd(y, _mm512_fnmadd_pd(_mm512_mul_pd(half_x, y), y, _mm512_set1_pd(1.5)));
  return _mm512_mul_pd(y, _mm512_fnmadd_pd(_mm512_mul_pd(half_x, y), y, _mm512_set1_pd(1.5)));
}

// 6 x signed volume of (0, a, b, c): a . (b x c).
inline V det6(V ax, V ay, V az, V bx, V by, V bz, V cx, V cy, V cz) {
  const V nx = _mm512_fmsub_pd(by, cz, _mm512_mul_pd(bz, cy));
  const V ny = _mm512_fmsub_pd(bz, cx, _mm512_mul_pd(bx, cz));
  const V nz = _mm512_fmsub_pd(bx, cy, _mm512_mul_pd(by, cx));
  return _mm512_fmadd_pd(az, nz, _mm512_fmadd_pd(ay, ny, _mm512_mul_pd(ax, nx)));
}

// The edges e_i = x_i - x_0 of the tets of 8 lanes from the position
// records; with Nodal, also the sum of their vertices' q (the records' 4th
// entries).
template <bool Nodal>
[[gnu::always_inline]] inline void tet_edges(const double* rec, const int32_t* const (&q)[4], V (&e)[3][3], V& qsum) {
  constexpr int kScale = kRecord / 4;
  V x0, y0, z0, w;
  if constexpr (Nodal) gather4<kScale>(rec, q[0], x0, y0, z0, qsum);
  else gather3<kScale>(rec, q[0], x0, y0, z0);
  for (int i = 0; i < 3; ++i) {
    if constexpr (Nodal) {
      gather4<kScale>(rec, q[i + 1], e[i][0], e[i][1], e[i][2], w);
      qsum = _mm512_add_pd(qsum, w);
    } else {
      gather3<kScale>(rec, q[i + 1], e[i][0], e[i][1], e[i][2]);
    }
    e[i][0] = _mm512_sub_pd(e[i][0], x0), e[i][1] = _mm512_sub_pd(e[i][1], y0), e[i][2] = _mm512_sub_pd(e[i][2], z0);
  }
}

// 6 x signed volume of the tets of 8 lanes from the position records.
[[gnu::always_inline]] inline V tet_det6(const double* rec, const int32_t* const (&q)[4], V (&e)[3][3]) {
  V unused;
  tet_edges<false>(rec, q, e, unused);
  return det6(e[0][0], e[0][1], e[0][2], e[1][0], e[1][1], e[1][2], e[2][0], e[2][1], e[2][2]);
}


template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
void chunk_step(Avx512DoubleKernel::Data& D, const DoubleStepInputs& in, int32_t c, ChunkReaction& partial) {
  const int cur = D.cur, nxt = 1 - cur;
  const double* const rec = positions(D, cur);
  const double* const inc = increments(D, cur);
  double* const next_rec = positions(D, nxt);
  double* const next_inc = increments(D, nxt);
  const int32_t* const other = D.spring_other.data();
  const double* const spring_rest = D.spring_rest.data();
  const double* const spring_k = D.spring_k.data();
  const double* const spring_d = D.spring_d.data();
  for (int32_t g = 0; g < D.groups; ++g) {
    const int32_t p0 = c * D.chunk + g * kLanes;
    const V ux = _mm512_load_pd(&D.u[cur][0][p0]), uy = _mm512_load_pd(&D.u[cur][1][p0]),
            uz = _mm512_load_pd(&D.u[cur][2][p0]);
    const V dx = _mm512_load_pd(&D.d[cur][0][p0]), dy = _mm512_load_pd(&D.d[cur][1][p0]),
            dz = _mm512_load_pd(&D.d[cur][2][p0]);
    const V rx = _mm512_load_pd(&D.rest[0][p0]), ry = _mm512_load_pd(&D.rest[1][p0]),
            rz = _mm512_load_pd(&D.rest[2][p0]);
    // The same x = X + u as in the records.
    const V px = _mm512_add_pd(rx, ux), py = _mm512_add_pd(ry, uy), pz = _mm512_add_pd(rz, uz);
    V fx = _mm512_setzero_pd(), fy = fx, fz = fx;
    if constexpr (Gravity) {
      const V mass = _mm512_load_pd(&D.mass[p0]);
      fx = _mm512_mul_pd(mass, _mm512_set1_pd(in.gravity[0]));
      fy = _mm512_mul_pd(mass, _mm512_set1_pd(in.gravity[1]));
      fz = _mm512_mul_pd(mass, _mm512_set1_pd(in.gravity[2]));
    }

    // Springs + dampers: f = [k (L - r) + d (dv . l/L) / dt] l/L, l = x_q - x_p.
    const V inv_dt = _mm512_set1_pd(in.inv_dt);
    const int32_t spring_width = D.spring_width[c * D.groups + g];
    for (int32_t j = 0, e = D.spring_offset[c] + g * kLanes; j < spring_width; ++j, e += D.chunk) {
      V qx, qy, qz, qdx, qdy, qdz;
      gather3<1>(rec, other + e, qx, qy, qz);
      gather3<1>(inc, other + e, qdx, qdy, qdz);
      const V lx = _mm512_sub_pd(qx, px), ly = _mm512_sub_pd(qy, py), lz = _mm512_sub_pd(qz, pz);
      const V len2 = _mm512_fmadd_pd(lz, lz, _mm512_fmadd_pd(ly, ly, _mm512_mul_pd(lx, lx)));
      const V inv = inv_length(len2);
      const V length = _mm512_mul_pd(len2, inv);
      const V vx = _mm512_sub_pd(qdx, dx), vy = _mm512_sub_pd(qdy, dy), vz = _mm512_sub_pd(qdz, dz);
      const V dot = _mm512_fmadd_pd(vz, lz, _mm512_fmadd_pd(vy, ly, _mm512_mul_pd(vx, lx)));
      const V along = _mm512_mul_pd(_mm512_mul_pd(dot, inv), inv_dt);
      const V stretch = _mm512_sub_pd(length, _mm512_load_pd(spring_rest + e));
      const V tension =
          _mm512_fmadd_pd(_mm512_load_pd(spring_k + e), stretch, _mm512_mul_pd(_mm512_load_pd(spring_d + e), along));
      const V s = _mm512_mul_pd(tension, inv);
      fx = _mm512_fmadd_pd(s, lx, fx);
      fy = _mm512_fmadd_pd(s, ly, fy);
      fz = _mm512_fmadd_pd(s, lz, fz);
    }

    if constexpr (Volume != ElementTerm::None) {
      // Volume forces, summed per slice by tet_slice(); slices in order.
      for (int sl = 0; sl < kSlices; ++sl) take_forces(&D.tet_force[sl][4 * static_cast<size_t>(p0)], fx, fy, fz);
    }

    if constexpr (Tool != ToolTerm::None) {
      // Few points touch the tool: find them with one compare, then
      // add_tool_force() on those lanes, reaction summed per lane in order.
      __mmask8 touching;
      if constexpr (Tool == ToolTerm::Push) {
        const V ox = _mm512_sub_pd(px, _mm512_set1_pd(in.tool_center[0]));
        const V oy = _mm512_sub_pd(py, _mm512_set1_pd(in.tool_center[1]));
        const V oz = _mm512_sub_pd(pz, _mm512_set1_pd(in.tool_center[2]));
        const V dist2 = _mm512_fmadd_pd(oz, oz, _mm512_fmadd_pd(oy, oy, _mm512_mul_pd(ox, ox)));
        // A margin so that no lane the exact test accepts is missed.
        const double r = in.tool_radius * 1.001;
        touching = _mm512_cmp_pd_mask(dist2, _mm512_set1_pd(r * r), _CMP_LT_OQ);
      } else {
        const __m512i a = _mm512_castsi256_si512(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(tool_lane_flags<Tool>(in) + p0)));
        touching = static_cast<__mmask8>(_mm512_mask_cmp_epi32_mask(0xff, a, _mm512_setzero_si512(), _MM_CMPINT_NLT));
      }
      if (touching) {
        alignas(64) double f[3][kLanes], x[3][kLanes];
        _mm512_store_pd(f[0], fx), _mm512_store_pd(f[1], fy), _mm512_store_pd(f[2], fz);
        _mm512_store_pd(x[0], px), _mm512_store_pd(x[1], py), _mm512_store_pd(x[2], pz);
        for (int l = 0; l < kLanes; ++l) {
          if (!(touching >> l & 1)) continue;
          double xl[3] = {x[0][l], x[1][l], x[2][l]}, fl[3] = {f[0][l], f[1][l], f[2][l]};
          if (!add_tool_force<double, Tool>(in, p0 + l, xl, fl, partial)) continue;
          for (int k = 0; k < 3; ++k) f[k][l] = fl[k];
        }
        fx = _mm512_load_pd(f[0]), fy = _mm512_load_pd(f[1]), fz = _mm512_load_pd(f[2]);
      }
    }

    // Position Verlet with drag: d' = (1 - alpha dt) d + dt^2 F/m, u' = u + d'.
    // Fixed and padding points (1/m = 0) stay put.
    const V inv_mass = _mm512_load_pd(&D.inv_mass[p0]);
    const __mmask8 free = _mm512_cmp_pd_mask(inv_mass, _mm512_setzero_pd(), _CMP_GT_OQ);
    const V w = _mm512_mul_pd(inv_mass, _mm512_set1_pd(in.dt2));
    const V drag = _mm512_set1_pd(in.drag);
    const V ndx = _mm512_maskz_mov_pd(free, _mm512_fmadd_pd(w, fx, _mm512_mul_pd(drag, dx)));
    const V ndy = _mm512_maskz_mov_pd(free, _mm512_fmadd_pd(w, fy, _mm512_mul_pd(drag, dy)));
    const V ndz = _mm512_maskz_mov_pd(free, _mm512_fmadd_pd(w, fz, _mm512_mul_pd(drag, dz)));
    const V nux = _mm512_add_pd(ux, ndx), nuy = _mm512_add_pd(uy, ndy), nuz = _mm512_add_pd(uz, ndz);
    _mm512_store_pd(&D.u[nxt][0][p0], nux), _mm512_store_pd(&D.u[nxt][1][p0], nuy);
    _mm512_store_pd(&D.u[nxt][2][p0], nuz);
    _mm512_store_pd(&D.d[nxt][0][p0], ndx), _mm512_store_pd(&D.d[nxt][1][p0], ndy);
    _mm512_store_pd(&D.d[nxt][2][p0], ndz);
    store_records(next_rec, next_inc, p0, _mm512_add_pd(rx, nux), _mm512_add_pd(ry, nuy), _mm512_add_pd(rz, nuz),
                  ndx, ndy, ndz);
  }
}

// The nodal term's first pass over one slice's tets: S of each vertex (its
// 4th entry in the slice's force array) += 6 V_t of the tet, from the
// position records at `rec`. pack() runs it on the rest records for
// node_rest, so the rest state gives exactly q = 0.
void nodal_volume_slice(Avx512DoubleKernel::Data& D, const double* rec, int slice) {
  double* const force = D.tet_force[slice].data();
  const int32_t* const tet_v[4] = {D.tet_v[0].data(), D.tet_v[1].data(), D.tet_v[2].data(), D.tet_v[3].data()};
  const int32_t end = D.slice_begin[slice + 1];
  for (int32_t b = D.slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[4] = {tet_v[0] + e, tet_v[1] + e, tet_v[2] + e, tet_v[3] + e};
    V unused[3][3];
    alignas(64) double det[kLanes];
    _mm512_store_pd(det, tet_det6(rec, q, unused));
    // One double per vertex: plain adds (the 8 vertices of a batch are distinct).
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < kLanes; ++l) force[q[k][l] + 3] += det[l];
  }
}

// S of point p: the slices' parts added in order (thread-count independent).
inline double nodal_volume_sum(const Avx512DoubleKernel::Data& D, int32_t p) {
  double s = D.tet_force[0][4 * static_cast<size_t>(p) + 3];
  for (int sl = 1; sl < kSlices; ++sl) s += D.tet_force[sl][4 * static_cast<size_t>(p) + 3];
  return s;
}

// The nodal term's second pass, per point of chunk c: q = node_k (S - S_r)
// into the 4th entry of its position record for the force pass to gather.
// S stays in the force arrays until take_forces() clears them.
void nodal_pressure_chunk(Avx512DoubleKernel::Data& D, int32_t c) {
  double* const rec = positions(D, D.cur);
  const int32_t first = c * D.chunk, last = first + D.chunk;
  for (int32_t p = first; p < last; ++p)
    rec[kRecord * static_cast<size_t>(p) + 3] = D.node_k[p] * (nodal_volume_sum(D, p) - D.node_rest[p]);
}

// Volume forces of one slice's tets into its force array: with
// V = e1 . (e2 x e3) / 6, e_i = x_i - x_0, dV/dx_1 = e2 x e3 / 6 (and
// cyclically) and f_0 = -(f_1 + f_2 + f_3). Per tet f_i = k_v (V_r - V)
// dV/dx_i; nodal f_i = -p_t dV/dx_i, p_t the mean of its vertices' pressures,
// whose scaled q the records carry.
template <ElementTerm Volume>
void tet_slice(Avx512DoubleKernel::Data& D, int slice) {
  // Local pointers: the intrinsic stores may alias anything, so pointers
  // read through D would be reloaded after every store.
  const double* const rec = positions(D, D.cur);
  double* const force = D.tet_force[slice].data();
  const int32_t* const tet_v[4] = {D.tet_v[0].data(), D.tet_v[1].data(), D.tet_v[2].data(), D.tet_v[3].data()};
  const double* const k36 = D.tet_k36.data();
  const double* const det_rest = D.tet_det_rest.data();
  const int32_t end = D.slice_begin[slice + 1];
  for (int32_t b = D.slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[4] = {tet_v[0] + e, tet_v[1] + e, tet_v[2] + e, tet_v[3] + e};
    V ev[3][3], s;
    if constexpr (Volume == ElementTerm::NodalVolume) {
      tet_edges<true>(rec, q, ev, s);  // s = the sum of the four q = -p_t / 6
    } else {
      const V det = tet_det6(rec, q, ev);
      s = _mm512_mul_pd(_mm512_load_pd(k36 + e), _mm512_sub_pd(_mm512_load_pd(det_rest + e), det));
    }
    auto cross_scaled = [&](const V (&a)[3], const V (&b)[3], V& fx, V& fy, V& fz) {
      fx = _mm512_mul_pd(s, _mm512_fmsub_pd(a[1], b[2], _mm512_mul_pd(a[2], b[1])));
      fy = _mm512_mul_pd(s, _mm512_fmsub_pd(a[2], b[0], _mm512_mul_pd(a[0], b[2])));
      fz = _mm512_mul_pd(s, _mm512_fmsub_pd(a[0], b[1], _mm512_mul_pd(a[1], b[0])));
    };
    V f1x, f1y, f1z, f2x, f2y, f2z, f3x, f3y, f3z;
    cross_scaled(ev[1], ev[2], f1x, f1y, f1z);  // e2 x e3
    cross_scaled(ev[2], ev[0], f2x, f2y, f2z);  // e3 x e1
    cross_scaled(ev[0], ev[1], f3x, f3y, f3z);  // e1 x e2
    const V zero = _mm512_setzero_pd();
    const V f0x = _mm512_sub_pd(zero, _mm512_add_pd(_mm512_add_pd(f1x, f2x), f3x));
    const V f0y = _mm512_sub_pd(zero, _mm512_add_pd(_mm512_add_pd(f1y, f2y), f3y));
    const V f0z = _mm512_sub_pd(zero, _mm512_add_pd(_mm512_add_pd(f1z, f2z), f3z));
    scatter_add(force, q[0], f0x, f0y, f0z);
    scatter_add(force, q[1], f1x, f1y, f1z);
    scatter_add(force, q[2], f2x, f2y, f2z);
    scatter_add(force, q[3], f3x, f3y, f3z);
  }
}

template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
void step_all(Avx512DoubleKernel::Data& D, const DoubleStepInputs& in, int threads,
              std::vector<ChunkReaction>& partial) {
  const int32_t nchunk = D.nchunk;
#pragma omp parallel num_threads(threads)
  {
    if constexpr (Volume == ElementTerm::NodalVolume) {
      // Every nodal volume before any pressure, every pressure before any force.
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, positions(D, D.cur), sl);
#pragma omp for schedule(static)
      for (int32_t c = 0; c < nchunk; ++c) nodal_pressure_chunk(D, c);
    }
    if constexpr (Volume != ElementTerm::None) {
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) tet_slice<Volume>(D, sl);
    }
#pragma omp for schedule(static)
    for (int32_t c = 0; c < nchunk; ++c) {
      ChunkReaction r;
      chunk_step<Volume, Gravity, Tool>(D, in, c, r);
      if constexpr (Tool != ToolTerm::None) partial[c] = r;
    }
  }
}

template <ElementTerm Volume, bool Gravity>
void step_tool(Avx512DoubleKernel::Data& D, const DoubleStepInputs& in, int threads,
               std::vector<ChunkReaction>& partial) {
  switch (in.tool) {
    case ToolTerm::Push: return step_all<Volume, Gravity, ToolTerm::Push>(D, in, threads, partial);
    case ToolTerm::Pull: return step_all<Volume, Gravity, ToolTerm::Pull>(D, in, threads, partial);
    case ToolTerm::Surface: return step_all<Volume, Gravity, ToolTerm::Surface>(D, in, threads, partial);
    default: return step_all<Volume, Gravity, ToolTerm::None>(D, in, threads, partial);
  }
}

template <ElementTerm Volume>
void step_gravity(Avx512DoubleKernel::Data& D, const DoubleStepInputs& in, int threads,
                  std::vector<ChunkReaction>& partial) {
  if (D.gravity) step_tool<Volume, true>(D, in, threads, partial);
  else step_tool<Volume, false>(D, in, threads, partial);
}

// The record of point p for the state in buffer b.
void write_record(Avx512DoubleKernel::Data& D, int b, int32_t p) {
  double* r = positions(D, b) + kRecord * static_cast<size_t>(p);
  double* i = increments(D, b) + kRecord * static_cast<size_t>(p);
  for (int k = 0; k < 3; ++k) {
    r[k] = D.rest[k][p] + D.u[b][k][p];
    i[k] = D.d[b][k][p];
  }
  r[3] = i[3] = 0;
}

}  // namespace

void Avx512DoubleKernel::set_point(int32_t p, const double u[3], const double d[3]) {
  Data& D = *data_;
  for (int k = 0; k < 3; ++k) {
    D.u[D.cur][k][p] = u[k];
    D.d[D.cur][k][p] = d[k];
  }
  write_record(D, D.cur, p);
}

void Avx512DoubleKernel::step(const DoubleStepInputs& in, int threads, std::vector<ChunkReaction>& partial) {
  Data& D = *data_;
  switch (D.volume) {
    case ElementTerm::NodalVolume: step_gravity<ElementTerm::NodalVolume>(D, in, threads, partial); break;
    case ElementTerm::TetVolume: step_gravity<ElementTerm::TetVolume>(D, in, threads, partial); break;
    default: step_gravity<ElementTerm::None>(D, in, threads, partial); break;
  }
  D.cur = 1 - D.cur;
}

void Avx512DoubleKernel::pack(const Model& model, const StepPlan& plan) {
  Data& D = *data_;
  const GatherLayout& L = model.layout;
  const int32_t old_npoint = D.npoint;
  D.npoint = model.npoint();
  D.chunk = L.chunk_size;
  D.nchunk = L.nchunk;
  D.groups = L.chunk_size / kLanes;
  D.npad = D.nchunk * D.chunk;
  D.volume = plan.element;
  D.gravity = plan.gravity;
  const size_t n = static_cast<size_t>(D.npad);

  // Points: padding lanes past npoint have no mass and stay at the origin.
  for (int k = 0; k < 3; ++k) {
    D.rest[k].assign(n, 0.0);
    for (int32_t p = 0; p < D.npoint; ++p) D.rest[k][p] = model.rest_position[p][k];
  }
  D.mass.assign(n, 0.0);
  D.inv_mass.assign(n, 0.0);
  std::copy(model.mass.begin(), model.mass.end(), D.mass.begin());
  std::copy(model.inv_mass.begin(), model.inv_mass.end(), D.inv_mass.begin());
  // State: kept for the points it held, zero for new ones (the caller sets them).
  for (int b = 0; b < 2; ++b) {
    for (int k = 0; k < 3; ++k) {
      D.u[b][k].resize(n, 0.0);
      D.d[b][k].resize(n, 0.0);
      std::fill(D.u[b][k].begin() + std::min(old_npoint, D.npoint), D.u[b][k].end(), 0.0);
      std::fill(D.d[b][k].begin() + std::min(old_npoint, D.npoint), D.d[b][k].end(), 0.0);
    }
    D.rec[b].assign(kRecord * (n + kLanes), 0.0);
    D.inc[b].assign(kRecord == 8 ? 0 : 4 * (n + kLanes), 0.0);
  }
  // The other buffer (overwritten by the next step) holds the rest records
  // while the rest lengths and volumes are computed from them.
  double* rec = positions(D, 1 - D.cur);
  for (int32_t p = 0; p < D.npad; ++p)
    for (int k = 0; k < 3; ++k) rec[kRecord * static_cast<size_t>(p) + k] = D.rest[k][p];

  // Slots per group of 8 lanes: the widest point of the group.
  D.spring_width.assign(static_cast<size_t>(D.nchunk) * D.groups, 0);
  for (int32_t p = 0; p < D.npoint; ++p) {
    const size_t g = static_cast<size_t>(p / D.chunk) * D.groups + (p % D.chunk) / kLanes;
    D.spring_width[g] = std::max(D.spring_width[g], L.springs.count[p]);
  }
  D.spring_offset.assign(L.springs.chunk_offset.begin(), L.springs.chunk_offset.end());

  // Per-slot streams; padding slots point at their own point with zero
  // stiffness (a zero-length spring and a flat tet add nothing). Rest lengths
  // and volumes come from the kernel's own arithmetic on the rest records, so
  // the rest state is exactly force-free.
  const size_t ns = L.springs.item.size();
  D.spring_other.resize(ns);
  D.spring_rest.assign(ns, 0.0);
  D.spring_k.assign(ns, 0.0);
  D.spring_d.assign(ns, 0.0);
  for (size_t e = 0; e < ns; ++e) {
    const int32_t s = L.springs.item[e];
    D.spring_other[e] =
        kRecord * (s < 0 ? point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e)) : L.spring_other[e]);
    if (s < 0) continue;
    D.spring_k[e] = model.spring_k[s];
    D.spring_d[e] = model.spring_d[s];
  }
  for (size_t e0 = 0; e0 < ns; e0 += kLanes) {
    const int32_t p0 = point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e0));
    V qx, qy, qz;
    gather3<1>(rec, &D.spring_other[e0], qx, qy, qz);
    const V lx = _mm512_sub_pd(qx, _mm512_load_pd(&D.rest[0][p0]));
    const V ly = _mm512_sub_pd(qy, _mm512_load_pd(&D.rest[1][p0]));
    const V lz = _mm512_sub_pd(qz, _mm512_load_pd(&D.rest[2][p0]));
    const V len2 = _mm512_fmadd_pd(lz, lz, _mm512_fmadd_pd(ly, ly, _mm512_mul_pd(lx, lx)));
    _mm512_store_pd(&D.spring_rest[e0], _mm512_mul_pd(len2, inv_length(len2)));
  }

  // Tets in batches of 8 (see Data and tet_batches.h).
  const TetBatches batches = batch_model_tets(model, kLanes, kSlices);
  std::copy(batches.slice_begin.begin(), batches.slice_begin.end(), D.slice_begin);
  const size_t lanes = batches.lane_tet.size();
  for (auto& v : D.tet_v) v.assign(lanes, 4 * D.npad);  // padding lanes: the zero record at npad
  const size_t per_tet = D.volume == ElementTerm::TetVolume ? lanes : 0;
  D.tet_k36.assign(per_tet, 0.0);
  D.tet_det_rest.assign(per_tet, 0.0);
  for (size_t e = 0; e < lanes; ++e) {
    const int32_t t = batches.lane_tet[e];
    if (t < 0) continue;
    for (int k = 0; k < 4; ++k) D.tet_v[k][e] = 4 * model.tet_points[t][k];
    if (per_tet) D.tet_k36[e] = model.tet_k[t] / 36;
  }
  for (size_t e0 = 0; e0 < per_tet; e0 += kLanes) {
    const int32_t* const q[4] = {&D.tet_v[0][e0], &D.tet_v[1][e0], &D.tet_v[2][e0], &D.tet_v[3][e0]};
    V unused[3][3];
    _mm512_store_pd(&D.tet_det_rest[e0], tet_det6(rec, q, unused));
  }
  for (auto& f : D.tet_force) f.assign(4 * (n + kLanes), 0.0);
  D.node_k.assign(D.volume == ElementTerm::NodalVolume ? n : 0, 0.0);
  D.node_rest.assign(D.node_k.size(), 0.0);
  if (D.volume == ElementTerm::NodalVolume) {
    // S at rest by the step's own passes, so that q is exactly 0 there.
    for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, rec, sl);
    for (int32_t p = 0; p < D.npoint; ++p) {
      D.node_k[p] = -model.point_volume_k[p] / 576;
      D.node_rest[p] = nodal_volume_sum(D, p);
    }
    for (auto& f : D.tet_force) std::fill(f.begin(), f.end(), 0.0);
  }
  for (int32_t p = 0; p < D.npad; ++p) write_record(D, D.cur, p);
}

#else  // no AVX-512 in this build: the backend never constructs the kernel

void Avx512DoubleKernel::set_point(int32_t, const double*, const double*) {}
void Avx512DoubleKernel::step(const DoubleStepInputs&, int, std::vector<ChunkReaction>&) {}
void Avx512DoubleKernel::pack(const Model&, const StepPlan&) {}

#endif

}  // namespace organsim
