#include "core/sim/cpu_kernel_avx512.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/sim/tet_batches.h"
#include "core/util/aligned_vector.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__)
#define ORGANSIM_HAVE_AVX512 1
// GCC 12's AVX-512 intrinsics fill unused operands with _mm512_undefined_ps(),
// which -Wuninitialized reports at every inlined use (a known false positive).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <immintrin.h>
#include <omp.h>
#endif

namespace organsim {

namespace {

constexpr int32_t kLanes = 16;  // floats per 512-bit register
// Tets are split into this many fixed slices, each summed into its own force
// array: the threads share the slices, and the per-point total adds the
// slices in order, so results do not depend on the thread count.
constexpr int kSlices = 2;

}  // namespace

std::string avx512_kernel_unsupported(const StepPlan& plan, int32_t chunk_size) {
  // Sutures are tension-only springs with a rest length on a schedule; this
  // kernel has neither, so the generic kernel runs a model that has them.
  if (plan.sutures > 0) return "the model has sutures (tension-only springs), which only the generic kernel runs";
  if (chunk_size % kLanes != 0)
    return "layout chunk size " + std::to_string(chunk_size) + " is not a multiple of " + std::to_string(kLanes);
  if (plan.shear()) return "the shear element (poisson_ratio < 0.25) runs on the generic kernel only";
  return "";
}

std::string avx512_kernel_unsupported(const Model& model) {
  return avx512_kernel_unsupported(make_step_plan(model, BackendTool{}), model.layout.chunk_size);
}

struct Avx512FloatKernel::Data {
  int32_t npoint = 0, npad = 0, chunk = 0, nchunk = 0, groups = 0;  // groups of 16 per chunk
  ElementTerm volume = ElementTerm::None;
  bool gravity = false;
  AlignedVector<float> rest[3], mass, inv_mass;  // (npad)
  AlignedVector<float> u[2][3], d[2][3];         // state, double-buffered (npad)
  // (x, y, z, q, dx, dy, dz, 0) per point, double-buffered (8 (npad + 16));
  // q is the nodal term's scaled pressure (node_k), 0 without it. The record
  // at npad stays zero: padding tets point at it.
  AlignedVector<float> rec[2];
  int cur = 0;                                   // which buffer holds step t
  std::vector<int32_t> spring_offset;            // first entry of each chunk (nchunk)
  std::vector<int32_t> spring_width;             // slots per group of 16 (nchunk x groups)
  // Indices are kept pre-scaled to float offsets (8 p into the records, 4 p
  // into the force slices), so an address costs no shift in the inner loops.
  AlignedVector<int32_t> spring_other;           // 8 x other end per entry; padding points at itself
  AlignedVector<float> spring_rest, spring_k, spring_d;
  // Tets, each evaluated once, 16 per batch: 16 nearby tets that share no
  // vertex (batch_tets()); each slice is a run of tets by lowest vertex.
  AlignedVector<int32_t> tet_v[4];               // 4 x vertex per batch lane; padding lanes: 4 npad
  AlignedVector<float> tet_k36, tet_det_rest;    // per tet: k_v / 36 and 6 V_r as the kernel computes it; else empty
  // Nodal term: q = node_k (S - node_rest) per point, S the sum of 6 V_t over
  // its tets, node_k = -k_a / 576 (so that a tet's four q add up to
  // -p_t / 6, its force factor), node_rest = S at rest as the kernel computes
  // it (npad); else empty.
  AlignedVector<float> node_k, node_rest;
  int32_t slice_begin[kSlices + 1] = {};         // batches of each slice
  // (x, y, z, S) per point, zero between steps (4 (npad + 16)): the tet
  // forces, and with the nodal term the slice's part of S.
  AlignedVector<float> tet_force[kSlices];
};

Avx512FloatKernel::Avx512FloatKernel() : data_(std::make_unique<Data>()) {}
Avx512FloatKernel::~Avx512FloatKernel() = default;

int32_t Avx512FloatKernel::nchunk() const { return data_->nchunk; }

size_t Avx512FloatKernel::bytes() const {
  const Data& D = *data_;
  const size_t n = static_cast<size_t>(D.npad);
  return n * sizeof(float) * (3 + 2 + 12 + 16 + 4 * kSlices) +
         D.spring_other.size() * (sizeof(int32_t) + 3 * sizeof(float)) +
         D.tet_v[0].size() * 4 * sizeof(int32_t) + (D.tet_k36.size() + D.tet_det_rest.size()) * sizeof(float) +
         (D.node_k.size() + D.node_rest.size()) * sizeof(float);
}

void Avx512FloatKernel::get_point(int32_t p, float u[3], float d[3]) const {
  const Data& D = *data_;
  for (int k = 0; k < 3; ++k) {
    u[k] = D.u[D.cur][k][p];
    d[k] = D.d[D.cur][k][p];
  }
}

#if ORGANSIM_HAVE_AVX512

bool avx512_kernel_compiled() { return true; }

namespace {

using V = __m512;

// Neighbour positions and increments of 16 points from their 32-byte
// records: eight 512-bit registers of two records each, transposed in
// registers. Register i holds records (q_i, q_{i+4}) for i < 4 and
// (q_{i+4}, q_{i+8}) above, so the shuffles below leave lanes in q order.
[[gnu::always_inline]] inline void gather6(const float* rec, const int32_t* q, V& x, V& y, V& z, V& dx, V& dy, V& dz) {
  auto pair = [&](int a, int b) {
    return _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(rec + q[a])), _mm256_load_ps(rec + q[b]), 1);
  };
  const V r0 = pair(0, 4), r1 = pair(1, 5), r2 = pair(2, 6), r3 = pair(3, 7);
  const V r4 = pair(8, 12), r5 = pair(9, 13), r6 = pair(10, 14), r7 = pair(11, 15);
  const V t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const V t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  const V t4 = _mm512_unpacklo_ps(r4, r5), t5 = _mm512_unpackhi_ps(r4, r5);
  const V t6 = _mm512_unpacklo_ps(r6, r7), t7 = _mm512_unpackhi_ps(r6, r7);
  // Per 128-bit quarter: x of 4 points, then dx of the same 4, and so on.
  const V sx0 = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  const V sy0 = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  const V sz0 = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  const V sx1 = _mm512_shuffle_ps(t4, t6, _MM_SHUFFLE(1, 0, 1, 0));
  const V sy1 = _mm512_shuffle_ps(t4, t6, _MM_SHUFFLE(3, 2, 3, 2));
  const V sz1 = _mm512_shuffle_ps(t5, t7, _MM_SHUFFLE(1, 0, 1, 0));
  x = _mm512_shuffle_f32x4(sx0, sx1, _MM_SHUFFLE(2, 0, 2, 0));
  y = _mm512_shuffle_f32x4(sy0, sy1, _MM_SHUFFLE(2, 0, 2, 0));
  z = _mm512_shuffle_f32x4(sz0, sz1, _MM_SHUFFLE(2, 0, 2, 0));
  dx = _mm512_shuffle_f32x4(sx0, sx1, _MM_SHUFFLE(3, 1, 3, 1));
  dy = _mm512_shuffle_f32x4(sy0, sy1, _MM_SHUFFLE(3, 1, 3, 1));
  dz = _mm512_shuffle_f32x4(sz0, sz1, _MM_SHUFFLE(3, 1, 3, 1));
}

// Neighbour positions and the records' 4th float (tets): 16-byte loads, four
// per register, and a 4 x 4 transpose inside each 128-bit quarter.
[[gnu::always_inline]] inline void gather4(const float* rec, const int32_t* q, V& x, V& y, V& z, V& w) {
  // 64-bit before the doubling, so that it folds into the load's addressing
  // (in 32 bits the compiler keeps the wrap-around: an add and a sign
  // extension per point, a sixth of the tet loop's instructions).
  auto at = [&](int l) { return rec + 2 * static_cast<ptrdiff_t>(q[l]); };
  auto quad = [&](int i) {
    V r = _mm512_castps128_ps512(_mm_load_ps(at(i)));
    r = _mm512_insertf32x4(r, _mm_load_ps(at(i + 4)), 1);
    r = _mm512_insertf32x4(r, _mm_load_ps(at(i + 8)), 2);
    return _mm512_insertf32x4(r, _mm_load_ps(at(i + 12)), 3);
  };
  const V r0 = quad(0), r1 = quad(1), r2 = quad(2), r3 = quad(3);
  const V t0 = _mm512_unpacklo_ps(r0, r1), t1 = _mm512_unpackhi_ps(r0, r1);
  const V t2 = _mm512_unpacklo_ps(r2, r3), t3 = _mm512_unpackhi_ps(r2, r3);
  x = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(1, 0, 1, 0));
  y = _mm512_shuffle_ps(t0, t2, _MM_SHUFFLE(3, 2, 3, 2));
  z = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(1, 0, 1, 0));
  w = _mm512_shuffle_ps(t1, t3, _MM_SHUFFLE(3, 2, 3, 2));
}
// Positions only (the unused shuffle for w is dropped by the compiler).
[[gnu::always_inline]] inline void gather3(const float* rec, const int32_t* q, V& x, V& y, V& z) {
  V unused;
  gather4(rec, q, x, y, z, unused);
}

// Writes the records of 16 consecutive points p0.. (the inverse transpose):
// each output register holds two consecutive records.
[[gnu::always_inline]] inline void store_records(float* rec, const V& x, const V& y, const V& z, const V& dx, const V& dy, const V& dz) {
  // Quarter k of s holds lane k of points (p, p+2, p+4, p+6) in the order
  // position, increment, position of the next point, its increment.
  const __m512i lo = _mm512_setr_epi32(0, 2, 4, 6, 16, 18, 20, 22, 1, 3, 5, 7, 17, 19, 21, 23);
  const __m512i hi = _mm512_add_epi32(lo, _mm512_set1_epi32(8));
  const V zero = _mm512_setzero_ps();
  for (int half = 0; half < 2; ++half) {
    const __m512i idx = half ? hi : lo;
    const V sx = _mm512_permutex2var_ps(x, idx, dx), sy = _mm512_permutex2var_ps(y, idx, dy);
    const V sz = _mm512_permutex2var_ps(z, idx, dz);
    const V u0 = _mm512_unpacklo_ps(sx, sy), u1 = _mm512_unpackhi_ps(sx, sy);
    const V u2 = _mm512_unpacklo_ps(sz, zero), u3 = _mm512_unpackhi_ps(sz, zero);
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
[[gnu::always_inline]] inline void add_quarter(const float* force, const int32_t* q, const V (&r)[4], __m128 (&sum)[kLanes]) {
  for (int i = 0; i < 4; ++i)
    sum[4 * Quarter + i] = _mm_add_ps(_mm_load_ps(force + q[4 * Quarter + i]),
                                      _mm512_extractf32x4_ps(r[i], Quarter));
}
[[gnu::always_inline]] inline void scatter_add(float* force, const int32_t* q, V x, V y, V z) {
  // The inverse of gather3: quarter k of r[i] is (x, y, z, 0) of lane 4k + i.
  const V zero = _mm512_setzero_ps();
  const V u0 = _mm512_unpacklo_ps(x, y), u1 = _mm512_unpackhi_ps(x, y);
  const V u2 = _mm512_unpacklo_ps(z, zero), u3 = _mm512_unpackhi_ps(z, zero);
  const V r[4] = {_mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u0, u2, _MM_SHUFFLE(3, 2, 3, 2)),
                  _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(1, 0, 1, 0)), _mm512_shuffle_ps(u1, u3, _MM_SHUFFLE(3, 2, 3, 2))};
  __m128 sum[kLanes];
  add_quarter<0>(force, q, r, sum);
  add_quarter<1>(force, q, r, sum);
  add_quarter<2>(force, q, r, sum);
  add_quarter<3>(force, q, r, sum);
  for (int l = 0; l < kLanes; ++l) _mm_store_ps(force + q[l], sum[l]);
}

// Adds the 16-byte forces of 16 consecutive points to (fx, fy, fz) and clears them.
[[gnu::always_inline]] inline void take_forces(float* force, V& fx, V& fy, V& fz) {
  const V l0 = _mm512_load_ps(force), l1 = _mm512_load_ps(force + 16), l2 = _mm512_load_ps(force + 32),
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

// 1/|l| for |l|^2 = len2 > 0, 0 otherwise (padding, coincident ends): the
// 14-bit estimate and one Newton step, ~1 ulp; the rest lengths are computed
// by this same function, so the rest state is force-free.
inline V inv_length(V len2) {
  const __mmask16 nonzero = _mm512_cmp_ps_mask(len2, _mm512_setzero_ps(), _CMP_GT_OQ);
  const V y = _mm512_maskz_rsqrt14_ps(nonzero, len2);
  const V half_x = _mm512_mul_ps(_mm512_set1_ps(0.5f), len2);
  // y (1.5 - x y^2 / 2)
  return _mm512_mul_ps(y, _mm512_fnmadd_ps(_mm512_mul_ps(half_x, y), y, _mm512_set1_ps(1.5f)));
}

// 6 x signed volume of (0, a, b, c): a . (b x c).
inline V det6(V ax, V ay, V az, V bx, V by, V bz, V cx, V cy, V cz) {
  const V nx = _mm512_fmsub_ps(by, cz, _mm512_mul_ps(bz, cy));
  const V ny = _mm512_fmsub_ps(bz, cx, _mm512_mul_ps(bx, cz));
  const V nz = _mm512_fmsub_ps(bx, cy, _mm512_mul_ps(by, cx));
  return _mm512_fmadd_ps(az, nz, _mm512_fmadd_ps(ay, ny, _mm512_mul_ps(ax, nx)));
}


template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
void chunk_step(Avx512FloatKernel::Data& D, const FloatStepInputs& in, int32_t c, ChunkReaction& partial) {
  const int cur = D.cur, nxt = 1 - cur;
  const float* rec = D.rec[cur].data();
  for (int32_t g = 0; g < D.groups; ++g) {
    const int32_t p0 = c * D.chunk + g * kLanes;
    const V ux = _mm512_load_ps(&D.u[cur][0][p0]), uy = _mm512_load_ps(&D.u[cur][1][p0]),
            uz = _mm512_load_ps(&D.u[cur][2][p0]);
    const V dx = _mm512_load_ps(&D.d[cur][0][p0]), dy = _mm512_load_ps(&D.d[cur][1][p0]),
            dz = _mm512_load_ps(&D.d[cur][2][p0]);
    const V rx = _mm512_load_ps(&D.rest[0][p0]), ry = _mm512_load_ps(&D.rest[1][p0]),
            rz = _mm512_load_ps(&D.rest[2][p0]);
    // The same x = X + u as in the records.
    const V px = _mm512_add_ps(rx, ux), py = _mm512_add_ps(ry, uy), pz = _mm512_add_ps(rz, uz);
    const V mass = _mm512_load_ps(&D.mass[p0]);
    V fx = _mm512_setzero_ps(), fy = fx, fz = fx;
    if constexpr (Gravity) {
      fx = _mm512_mul_ps(mass, _mm512_set1_ps(in.gravity[0]));
      fy = _mm512_mul_ps(mass, _mm512_set1_ps(in.gravity[1]));
      fz = _mm512_mul_ps(mass, _mm512_set1_ps(in.gravity[2]));
    }

    // Springs + dampers: f = [k (L - r) + d (dv . l/L) / dt] l/L, l = x_q - x_p.
    const V inv_dt = _mm512_set1_ps(in.inv_dt);
    const int32_t spring_width = D.spring_width[c * D.groups + g];
    for (int32_t j = 0, e = D.spring_offset[c] + g * kLanes; j < spring_width; ++j, e += D.chunk) {
      V qx, qy, qz, qdx, qdy, qdz;
      gather6(rec, &D.spring_other[e], qx, qy, qz, qdx, qdy, qdz);
      const V lx = _mm512_sub_ps(qx, px), ly = _mm512_sub_ps(qy, py), lz = _mm512_sub_ps(qz, pz);
      const V len2 = _mm512_fmadd_ps(lz, lz, _mm512_fmadd_ps(ly, ly, _mm512_mul_ps(lx, lx)));
      const V inv = inv_length(len2);
      const V length = _mm512_mul_ps(len2, inv);
      const V vx = _mm512_sub_ps(qdx, dx), vy = _mm512_sub_ps(qdy, dy), vz = _mm512_sub_ps(qdz, dz);
      const V dot = _mm512_fmadd_ps(vz, lz, _mm512_fmadd_ps(vy, ly, _mm512_mul_ps(vx, lx)));
      const V along = _mm512_mul_ps(_mm512_mul_ps(dot, inv), inv_dt);
      const V stretch = _mm512_sub_ps(length, _mm512_load_ps(&D.spring_rest[e]));
      const V tension = _mm512_fmadd_ps(_mm512_load_ps(&D.spring_k[e]), stretch,
                                        _mm512_mul_ps(_mm512_load_ps(&D.spring_d[e]), along));
      const V s = _mm512_mul_ps(tension, inv);
      fx = _mm512_fmadd_ps(s, lx, fx);
      fy = _mm512_fmadd_ps(s, ly, fy);
      fz = _mm512_fmadd_ps(s, lz, fz);
    }

    if constexpr (Volume != ElementTerm::None) {
      // Volume forces, summed per slice by tet_slice(); slices in order.
      for (int sl = 0; sl < kSlices; ++sl) take_forces(&D.tet_force[sl][4 * static_cast<size_t>(p0)], fx, fy, fz);
    }

    if constexpr (Tool != ToolTerm::None) {
      // Few points touch the tool: find them with one compare, then
      // add_tool_force() on those lanes, reaction summed per lane in order.
      __mmask16 touching;
      if constexpr (Tool == ToolTerm::Push) {
        const V cx = _mm512_set1_ps(in.tool_center[0]), cy = _mm512_set1_ps(in.tool_center[1]),
                cz = _mm512_set1_ps(in.tool_center[2]);
        const V ox = _mm512_sub_ps(px, cx), oy = _mm512_sub_ps(py, cy), oz = _mm512_sub_ps(pz, cz);
        const V dist2 = _mm512_fmadd_ps(oz, oz, _mm512_fmadd_ps(oy, oy, _mm512_mul_ps(ox, ox)));
        // A margin so that no lane the exact test below accepts is missed.
        const float r = in.tool_radius * 1.001f;
        touching = _mm512_cmp_ps_mask(dist2, _mm512_set1_ps(r * r), _CMP_LT_OQ);
      } else {
        const __m512i a = _mm512_loadu_si512(tool_lane_flags<Tool>(in) + p0);
        touching = _mm512_cmp_epi32_mask(a, _mm512_setzero_si512(), _MM_CMPINT_NLT);
      }
      if (touching) {
        alignas(64) float f[3][kLanes], x[3][kLanes];
        _mm512_store_ps(f[0], fx), _mm512_store_ps(f[1], fy), _mm512_store_ps(f[2], fz);
        _mm512_store_ps(x[0], px), _mm512_store_ps(x[1], py), _mm512_store_ps(x[2], pz);
        for (int l = 0; l < kLanes; ++l) {
          if (!(touching >> l & 1)) continue;
          float xl[3] = {x[0][l], x[1][l], x[2][l]}, fl[3] = {f[0][l], f[1][l], f[2][l]};
          if (!add_tool_force<float, Tool>(in, p0 + l, xl, fl, partial)) continue;
          for (int k = 0; k < 3; ++k) f[k][l] = fl[k];
        }
        fx = _mm512_load_ps(f[0]), fy = _mm512_load_ps(f[1]), fz = _mm512_load_ps(f[2]);
      }
    }

    // Position Verlet with drag: d' = (1 - alpha dt) d + dt^2 F/m, u' = u + d'.
    // Fixed and padding points (1/m = 0) stay put.
    const V inv_mass = _mm512_load_ps(&D.inv_mass[p0]);
    const __mmask16 free = _mm512_cmp_ps_mask(inv_mass, _mm512_setzero_ps(), _CMP_GT_OQ);
    const V w = _mm512_mul_ps(inv_mass, _mm512_set1_ps(in.dt2));
    const V drag = _mm512_set1_ps(in.drag);
    const V ndx = _mm512_maskz_mov_ps(free, _mm512_fmadd_ps(w, fx, _mm512_mul_ps(drag, dx)));
    const V ndy = _mm512_maskz_mov_ps(free, _mm512_fmadd_ps(w, fy, _mm512_mul_ps(drag, dy)));
    const V ndz = _mm512_maskz_mov_ps(free, _mm512_fmadd_ps(w, fz, _mm512_mul_ps(drag, dz)));
    const V nux = _mm512_add_ps(ux, ndx), nuy = _mm512_add_ps(uy, ndy), nuz = _mm512_add_ps(uz, ndz);
    _mm512_store_ps(&D.u[nxt][0][p0], nux), _mm512_store_ps(&D.u[nxt][1][p0], nuy);
    _mm512_store_ps(&D.u[nxt][2][p0], nuz);
    _mm512_store_ps(&D.d[nxt][0][p0], ndx), _mm512_store_ps(&D.d[nxt][1][p0], ndy);
    _mm512_store_ps(&D.d[nxt][2][p0], ndz);
    store_records(D.rec[nxt].data() + 8 * p0, _mm512_add_ps(rx, nux), _mm512_add_ps(ry, nuy),
                  _mm512_add_ps(rz, nuz), ndx, ndy, ndz);
  }
}

// The nodal term's first pass over one slice's tets: S of each vertex (its
// 4th float in the slice's force array) += 6 V_t of the tet, from the
// records at `rec`. pack() runs it on the rest records for node_rest, so
// the rest state gives exactly q = 0.
void nodal_volume_slice(Avx512FloatKernel::Data& D, const float* rec, int slice) {
  float* const force = D.tet_force[slice].data();
  const int32_t* const tet_v[4] = {D.tet_v[0].data(), D.tet_v[1].data(), D.tet_v[2].data(), D.tet_v[3].data()};
  const int32_t end = D.slice_begin[slice + 1];
  for (int32_t b = D.slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[4] = {tet_v[0] + e, tet_v[1] + e, tet_v[2] + e, tet_v[3] + e};
    V x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3;
    gather3(rec, q[0], x0, y0, z0);
    gather3(rec, q[1], x1, y1, z1);
    gather3(rec, q[2], x2, y2, z2);
    gather3(rec, q[3], x3, y3, z3);
    alignas(64) float det[kLanes];
    _mm512_store_ps(det, det6(_mm512_sub_ps(x1, x0), _mm512_sub_ps(y1, y0), _mm512_sub_ps(z1, z0),
                              _mm512_sub_ps(x2, x0), _mm512_sub_ps(y2, y0), _mm512_sub_ps(z2, z0),
                              _mm512_sub_ps(x3, x0), _mm512_sub_ps(y3, y0), _mm512_sub_ps(z3, z0)));
    // One float per vertex: plain adds (the 16 vertices of a batch are distinct).
    for (int k = 0; k < 4; ++k)
      for (int l = 0; l < kLanes; ++l) force[q[k][l] + 3] += det[l];
  }
}

// S of point p: the slices' parts added in order (thread-count independent).
inline float nodal_volume_sum(const Avx512FloatKernel::Data& D, int32_t p) {
  float s = D.tet_force[0][4 * static_cast<size_t>(p) + 3];
  for (int sl = 1; sl < kSlices; ++sl) s += D.tet_force[sl][4 * static_cast<size_t>(p) + 3];
  return s;
}

// The nodal term's second pass, per point of chunk c: q = node_k (S - S_r)
// into the 4th float of its record for the force pass to gather. S stays in
// the force arrays until take_forces() clears them.
void nodal_pressure_chunk(Avx512FloatKernel::Data& D, int32_t c) {
  float* const rec = D.rec[D.cur].data();
  const int32_t first = c * D.chunk, last = first + D.chunk;
  for (int32_t p = first; p < last; ++p)
    rec[8 * static_cast<size_t>(p) + 3] = D.node_k[p] * (nodal_volume_sum(D, p) - D.node_rest[p]);
}

// Volume forces of one slice's tets into its force array: with
// V = e1 . (e2 x e3) / 6, e_i = x_i - x_0, dV/dx_1 = e2 x e3 / 6 (and
// cyclically) and f_0 = -(f_1 + f_2 + f_3). Per tet f_i = k_v (V_r - V)
// dV/dx_i; nodal f_i = -p_t dV/dx_i, p_t the mean of its vertices' pressures,
// whose scaled q the records carry.
template <ElementTerm Volume>
void tet_slice(Avx512FloatKernel::Data& D, int slice) {
  // Local pointers: the intrinsic stores may alias anything, so pointers
  // read through D would be reloaded after every store.
  const float* const rec = D.rec[D.cur].data();
  float* const force = D.tet_force[slice].data();
  const int32_t* const tet_v[4] = {D.tet_v[0].data(), D.tet_v[1].data(), D.tet_v[2].data(), D.tet_v[3].data()};
  const float* const k36 = D.tet_k36.data();
  const float* const det_rest = D.tet_det_rest.data();
  const int32_t end = D.slice_begin[slice + 1];
  for (int32_t b = D.slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[4] = {tet_v[0] + e, tet_v[1] + e, tet_v[2] + e, tet_v[3] + e};
    V x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3;
    V s;
    if constexpr (Volume == ElementTerm::NodalVolume) {
      V q0, q1, q2, q3;
      gather4(rec, q[0], x0, y0, z0, q0);
      gather4(rec, q[1], x1, y1, z1, q1);
      gather4(rec, q[2], x2, y2, z2, q2);
      gather4(rec, q[3], x3, y3, z3, q3);
      s = _mm512_add_ps(_mm512_add_ps(_mm512_add_ps(q0, q1), q2), q3);  // -p_t / 6
    } else {
      gather3(rec, q[0], x0, y0, z0);
      gather3(rec, q[1], x1, y1, z1);
      gather3(rec, q[2], x2, y2, z2);
      gather3(rec, q[3], x3, y3, z3);
    }
    x1 = _mm512_sub_ps(x1, x0), y1 = _mm512_sub_ps(y1, y0), z1 = _mm512_sub_ps(z1, z0);
    x2 = _mm512_sub_ps(x2, x0), y2 = _mm512_sub_ps(y2, y0), z2 = _mm512_sub_ps(z2, z0);
    x3 = _mm512_sub_ps(x3, x0), y3 = _mm512_sub_ps(y3, y0), z3 = _mm512_sub_ps(z3, z0);
    if constexpr (Volume != ElementTerm::NodalVolume) {
      const V det = det6(x1, y1, z1, x2, y2, z2, x3, y3, z3);
      s = _mm512_mul_ps(_mm512_load_ps(k36 + e), _mm512_sub_ps(_mm512_load_ps(det_rest + e), det));
    }
    auto cross_scaled = [&](V ax, V ay, V az, V bx, V by, V bz, V& fx, V& fy, V& fz) {
      fx = _mm512_mul_ps(s, _mm512_fmsub_ps(ay, bz, _mm512_mul_ps(az, by)));
      fy = _mm512_mul_ps(s, _mm512_fmsub_ps(az, bx, _mm512_mul_ps(ax, bz)));
      fz = _mm512_mul_ps(s, _mm512_fmsub_ps(ax, by, _mm512_mul_ps(ay, bx)));
    };
    V f1x, f1y, f1z, f2x, f2y, f2z, f3x, f3y, f3z;
    cross_scaled(x2, y2, z2, x3, y3, z3, f1x, f1y, f1z);  // e2 x e3
    cross_scaled(x3, y3, z3, x1, y1, z1, f2x, f2y, f2z);  // e3 x e1
    cross_scaled(x1, y1, z1, x2, y2, z2, f3x, f3y, f3z);  // e1 x e2
    const V zero = _mm512_setzero_ps();
    const V f0x = _mm512_sub_ps(zero, _mm512_add_ps(_mm512_add_ps(f1x, f2x), f3x));
    const V f0y = _mm512_sub_ps(zero, _mm512_add_ps(_mm512_add_ps(f1y, f2y), f3y));
    const V f0z = _mm512_sub_ps(zero, _mm512_add_ps(_mm512_add_ps(f1z, f2z), f3z));
    scatter_add(force, q[0], f0x, f0y, f0z);
    scatter_add(force, q[1], f1x, f1y, f1z);
    scatter_add(force, q[2], f2x, f2y, f2z);
    scatter_add(force, q[3], f3x, f3y, f3z);
  }
}

template <ElementTerm Volume, bool Gravity, ToolTerm Tool>
void step_all(Avx512FloatKernel::Data& D, const FloatStepInputs& in, int threads,
              std::vector<ChunkReaction>& partial) {
  const int32_t nchunk = D.nchunk;
#pragma omp parallel num_threads(threads)
  {
    if constexpr (Volume == ElementTerm::NodalVolume) {
      // Every nodal volume before any pressure, every pressure before any force.
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, D.rec[D.cur].data(), sl);
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
void step_tool(Avx512FloatKernel::Data& D, const FloatStepInputs& in, int threads,
               std::vector<ChunkReaction>& partial) {
  switch (in.tool) {
    case ToolTerm::Push: return step_all<Volume, Gravity, ToolTerm::Push>(D, in, threads, partial);
    case ToolTerm::Pull: return step_all<Volume, Gravity, ToolTerm::Pull>(D, in, threads, partial);
    case ToolTerm::Surface: return step_all<Volume, Gravity, ToolTerm::Surface>(D, in, threads, partial);
    default: return step_all<Volume, Gravity, ToolTerm::None>(D, in, threads, partial);
  }
}

template <ElementTerm Volume>
void step_gravity(Avx512FloatKernel::Data& D, const FloatStepInputs& in, int threads,
                  std::vector<ChunkReaction>& partial) {
  if (D.gravity) step_tool<Volume, true>(D, in, threads, partial);
  else step_tool<Volume, false>(D, in, threads, partial);
}

// The record of point p for the state in buffer b.
void write_record(Avx512FloatKernel::Data& D, int b, int32_t p) {
  float* r = &D.rec[b][8 * static_cast<size_t>(p)];
  for (int k = 0; k < 3; ++k) {
    r[k] = D.rest[k][p] + D.u[b][k][p];
    r[4 + k] = D.d[b][k][p];
  }
  r[3] = r[7] = 0;
}

}  // namespace

void Avx512FloatKernel::set_point(int32_t p, const float u[3], const float d[3]) {
  Data& D = *data_;
  for (int k = 0; k < 3; ++k) {
    D.u[D.cur][k][p] = u[k];
    D.d[D.cur][k][p] = d[k];
  }
  write_record(D, D.cur, p);
}

void Avx512FloatKernel::step(const FloatStepInputs& in, int threads, std::vector<ChunkReaction>& partial) {
  Data& D = *data_;
  switch (D.volume) {
    case ElementTerm::NodalVolume: step_gravity<ElementTerm::NodalVolume>(D, in, threads, partial); break;
    case ElementTerm::TetVolume: step_gravity<ElementTerm::TetVolume>(D, in, threads, partial); break;
    default: step_gravity<ElementTerm::None>(D, in, threads, partial); break;
  }
  D.cur = 1 - D.cur;
}
void Avx512FloatKernel::pack(const Model& model, const StepPlan& plan) {
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
    D.rest[k].assign(n, 0.f);
    for (int32_t p = 0; p < D.npoint; ++p) D.rest[k][p] = static_cast<float>(model.rest_position[p][k]);
  }
  D.mass.assign(n, 0.f);
  D.inv_mass.assign(n, 0.f);
  for (int32_t p = 0; p < D.npoint; ++p) {
    D.mass[p] = static_cast<float>(model.mass[p]);
    D.inv_mass[p] = static_cast<float>(model.inv_mass[p]);
  }
  // State: kept for the points it held, zero for new ones (the caller sets them).
  for (int b = 0; b < 2; ++b) {
    for (int k = 0; k < 3; ++k) {
      D.u[b][k].resize(n, 0.f);
      D.d[b][k].resize(n, 0.f);
      std::fill(D.u[b][k].begin() + std::min(old_npoint, D.npoint), D.u[b][k].end(), 0.f);
      std::fill(D.d[b][k].begin() + std::min(old_npoint, D.npoint), D.d[b][k].end(), 0.f);
    }
    D.rec[b].assign(8 * (n + kLanes), 0.f);
  }
  // The other buffer (overwritten by the next step) holds the rest records
  // while the rest lengths and volumes are computed from them.
  float* rec = D.rec[1 - D.cur].data();
  for (int32_t p = 0; p < D.npad; ++p)
    for (int k = 0; k < 3; ++k) rec[8 * static_cast<size_t>(p) + k] = D.rest[k][p];

  // Slots per group of 16 lanes: the widest point of the group.
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
  D.spring_rest.assign(ns, 0.f);
  D.spring_k.assign(ns, 0.f);
  D.spring_d.assign(ns, 0.f);
  for (size_t e = 0; e < ns; ++e) {
    const int32_t s = L.springs.item[e];
    D.spring_other[e] = 8 * (s < 0 ? point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e)) : L.spring_other[e]);
    if (s < 0) continue;
    D.spring_k[e] = static_cast<float>(model.spring_k[s]);
    D.spring_d[e] = static_cast<float>(model.spring_d[s]);
  }
  for (size_t e0 = 0; e0 < ns; e0 += kLanes) {
    const int32_t p0 = point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e0));
    V qx, qy, qz, unused0, unused1, unused2;
    gather6(rec, &D.spring_other[e0], qx, qy, qz, unused0, unused1, unused2);
    const V lx = _mm512_sub_ps(qx, _mm512_load_ps(&D.rest[0][p0]));
    const V ly = _mm512_sub_ps(qy, _mm512_load_ps(&D.rest[1][p0]));
    const V lz = _mm512_sub_ps(qz, _mm512_load_ps(&D.rest[2][p0]));
    const V len2 = _mm512_fmadd_ps(lz, lz, _mm512_fmadd_ps(ly, ly, _mm512_mul_ps(lx, lx)));
    _mm512_store_ps(&D.spring_rest[e0], _mm512_mul_ps(len2, inv_length(len2)));
  }

  // Tets in batches of 16 (see Data and tet_batches.h).
  const TetBatches batches = batch_model_tets(model, kLanes, kSlices);
  const std::vector<int32_t>& lane_tet = batches.lane_tet;
  std::copy(batches.slice_begin.begin(), batches.slice_begin.end(), D.slice_begin);
  const size_t lanes = lane_tet.size();
  for (auto& v : D.tet_v) v.assign(lanes, 4 * D.npad);  // padding lanes: the zero record at npad
  const size_t per_tet = D.volume == ElementTerm::TetVolume ? lanes : 0;
  D.tet_k36.assign(per_tet, 0.f);
  D.tet_det_rest.assign(per_tet, 0.f);
  for (size_t e = 0; e < lanes; ++e) {
    const int32_t t = lane_tet[e];
    if (t < 0) continue;
    for (int k = 0; k < 4; ++k) D.tet_v[k][e] = 4 * model.tet_points[t][k];
    if (per_tet) D.tet_k36[e] = static_cast<float>(model.tet_k[t] / 36);
  }
  for (size_t e0 = 0; e0 < per_tet; e0 += kLanes) {
    V x0, y0, z0, x1, y1, z1, x2, y2, z2, x3, y3, z3;
    gather3(rec, &D.tet_v[0][e0], x0, y0, z0);
    gather3(rec, &D.tet_v[1][e0], x1, y1, z1);
    gather3(rec, &D.tet_v[2][e0], x2, y2, z2);
    gather3(rec, &D.tet_v[3][e0], x3, y3, z3);
    const V det = det6(_mm512_sub_ps(x1, x0), _mm512_sub_ps(y1, y0), _mm512_sub_ps(z1, z0), _mm512_sub_ps(x2, x0),
                       _mm512_sub_ps(y2, y0), _mm512_sub_ps(z2, z0), _mm512_sub_ps(x3, x0), _mm512_sub_ps(y3, y0),
                       _mm512_sub_ps(z3, z0));
    _mm512_store_ps(&D.tet_det_rest[e0], det);
  }
  for (auto& f : D.tet_force) f.assign(4 * (n + kLanes), 0.f);
  D.node_k.assign(D.volume == ElementTerm::NodalVolume ? n : 0, 0.f);
  D.node_rest.assign(D.node_k.size(), 0.f);
  if (D.volume == ElementTerm::NodalVolume) {
    // S at rest by the step's own passes, so that q is exactly 0 there.
    for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, rec, sl);
    for (int32_t p = 0; p < D.npoint; ++p) {
      D.node_k[p] = static_cast<float>(-model.point_volume_k[p] / 576);
      D.node_rest[p] = nodal_volume_sum(D, p);
    }
    for (auto& f : D.tet_force) std::fill(f.begin(), f.end(), 0.f);
  }
  for (int32_t p = 0; p < D.npad; ++p) write_record(D, D.cur, p);
}

#else  // no AVX-512 in this build: the backend never constructs the kernel

bool avx512_kernel_compiled() { return false; }
void Avx512FloatKernel::set_point(int32_t, const float*, const float*) {}
void Avx512FloatKernel::step(const FloatStepInputs&, int, std::vector<ChunkReaction>&) {}
void Avx512FloatKernel::pack(const Model&, const StepPlan&) {}

#endif

}  // namespace organsim
