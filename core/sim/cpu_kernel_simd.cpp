// The CPU kernel on Google Highway: one source, compiled once per target
// (hwy/foreach_target.h) into the namespaces N_SSE4, N_AVX2, N_AVX3,
// N_NEON, N_EMU128, ...; cpu_kernel_simd.h says what it does and
// simd_records-inl.h how it reads and writes its records.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "core/sim/cpu_kernel_simd.cpp"
// The targets before foreach_target.h (which re-includes this file once per
// target), in this order: not for clang-format to sort.
// clang-format off
#include "core/sim/simd_targets.h"
#include "hwy/foreach_target.h"  // IWYU pragma: keep
#include "hwy/highway.h"
// clang-format on

#include <omp.h>

#include <algorithm>
#include <array>
#include <map>

#include "core/model/shear_element.h"
#include "core/sim/cpu_kernel_simd.h"
#include "core/sim/simd_records-inl.h"
#include "core/sim/tet_batches.h"
#include "core/sim/tet_pairs.h"
#include "core/util/aligned_vector.h"

// Per-target part: everything below up to HWY_AFTER_NAMESPACE is compiled
// once for every target.
HWY_BEFORE_NAMESPACE();
namespace organsim::HWY_NAMESPACE {
namespace {

// Tets are split into this many fixed slices, each summed into its own force
// array: the threads share the slices, and the per-point total adds the
// slices in order, so results do not depend on the thread count.
constexpr int kSlices = 2;

// The smoothed shear element's per-point stress record: P_00, P_01, P_02,
// P_10, ..., P_21 (32 bytes in float, 64 in double), read by the tet pass
// with a load per block of each corner and a transpose (gather_values).
// P_22 rides in the displacement records' spare slot, the increment's 4th
// value (Data::stress_tail), which the tet pass gathers with u and d.
constexpr int kStressRecord = 8;

template <class Real>
struct Data {
  static constexpr int32_t kLanes = HWY_NAMESPACE::kLanes<Real>;  // per register of this target
  static constexpr int32_t kRecord = HWY_NAMESPACE::kRecord<Real>;  // values per point (simd_records-inl.h)
  static constexpr bool kSplit = HWY_NAMESPACE::kSplit<Real>;

  int32_t npoint = 0, npad = 0, chunk = 0, nchunk = 0, groups = 0;  // groups of kLanes per chunk
  ElementTerm element = ElementTerm::None;
  bool gravity = false, sutures = false, damped = false;
  Real shear_per_tet = 1, shear_corners = 0;     // smoothed shear: 1 - s and s / 4
  AlignedVector<Real> rest[3], mass, inv_mass;   // (npad)
  AlignedVector<Real> u[2][3], d[2][3];          // state, double-buffered (npad)
  // Records of x = X + u (and w), double-buffered (kRecord (npad + kLanes));
  // increments in their own array when split. The record at npad stays
  // zero: padding tets point at it.
  AlignedVector<Real> rec[2], inc[2];
  // The shear element reads displacements, in the same layout as the
  // records (u, 0 [, d, 0]), so that F = I exactly at rest; else empty.
  AlignedVector<Real> urec[2];
  int cur = 0;                                   // which buffer holds step t
  std::vector<int32_t> spring_offset;            // first entry of each chunk (nchunk)
  std::vector<int32_t> spring_width;             // slots per group (nchunk x groups)
  // Indices are kept pre-scaled to offsets (kRecord p into the records,
  // 4 p into the force slices), so an address costs no shift in the inner loops.
  AlignedVector<int32_t> spring_other;           // kRecord x other end per entry; padding points at itself
  AlignedVector<Real> spring_rest, spring_k, spring_d;  // k < 0 marks a suture (stiffness |k|, pulls only)
  // Smoothed shear: b = sum over the tets of (p, q) of k_t g_q / K_p per
  // slot (x, y, z), so that Fbar_p - I = sum over p's slots of
  // (u_q - u_p) b^T; else empty.
  AlignedVector<Real> spring_b[3];
  // The volume terms' tets, each evaluated once, kLanes per batch sharing no
  // vertex (batch_tets()); each slice is a run of tets by lowest vertex.
  AlignedVector<int32_t> tet_v[4];               // 4 x vertex per batch lane; padding lanes: 4 npad
  AlignedVector<Real> tet_k36, tet_det_rest;     // per-tet volume: k_v / 36 and 6 V_r as the kernel computes it; else empty
  // Shear element: tets in pairs (pair_v below), batches of kLanes pairs
  // sharing no point (shear_slice_begin); per lane the shape gradients of
  // b, c, d in the first tet and of c, b, e in the second (x, y, z each) and
  // each tet's k_t (tet2_*: zero for a lone tet); else empty.
  AlignedVector<Real> tet_g[9], tet_shear_k, tet2_g[9], tet2_shear_k;
  int32_t shear_slice_begin[kSlices + 1] = {};
  // Nodal term: q = node_k (S - node_rest) per point, S the sum of 6 V_t over
  // its tets, node_k = -k_a / 576 (so that a tet's four q add up to
  // -p_t / 6, its force factor), node_rest = S at rest as the kernel computes
  // it (npad); else empty.
  AlignedVector<Real> node_k, node_rest;
  // Tets in pairs that share a face (tet_pairs.h), kLanes pairs per batch,
  // for the nodal term's volume pass or the shear element's pass: points
  // (a, b, c, d, e) of each lane (4 x vertex; padding lanes 4 npad).
  AlignedVector<int32_t> pair_v[5];
  // Nodal term: the volume pass's output per batch, kLanes entries each of
  // 6 (V_1 + V_2), 6 V_1 and 6 V_2 (the entries past the batches stay zero);
  // each slice a run of batches.
  AlignedVector<Real> pair_det6;
  int32_t pair_slice_begin[kSlices + 1] = {};
  // Per point the entries its nodal volume sums (the shared face's points
  // the pair's sum, d and e their own tet's), in the springs' slot layout
  // (padding slots: the first zero entry), so that each point sums its tets'
  // volumes with loads instead of every tet scattering into its four points.
  AlignedVector<int32_t> node_entry;
  std::vector<int32_t> node_entry_offset, node_entry_width;  // as spring_offset and spring_width
  AlignedVector<Real> node_stress;               // smoothed shear: P(Fbar_p) records (kStressRecord (npad + 1), the last zero); else empty
  int32_t slice_begin[kSlices + 1] = {};         // batches of each slice
  // (x, y, z, 0) per point, zero between steps (4 (npad + kLanes)): the tet
  // forces of the slice.
  AlignedVector<Real> tet_force[kSlices];

  Real* positions(int b) { return rec[b].data(); }
  // Where point p's P_22 goes: the increment's 4th value beside its
  // displacement (float: slot 7 of the urec record; double: w of the
  // increment quad), every kRecord values.
  Real* stress_tail(int b) { return kSplit ? inc[b].data() + 3 : urec[b].data() + 7; }
  Real* increments(int b) { return kSplit ? inc[b].data() : rec[b].data() + 4; }
};


// 6 x signed volume of (0, a, b, c): a . (b x c).
template <class Real>
HWY_INLINE V<Real> det6(const V3<Real>& a, const V3<Real>& b, const V3<Real>& c) {
  const V<Real> nx = fmsub(b[1], c[2], b[2] * c[1]);
  const V<Real> ny = fmsub(b[2], c[0], b[0] * c[2]);
  const V<Real> nz = fmsub(b[0], c[1], b[1] * c[0]);
  return fmadd(a[2], nz, fmadd(a[1], ny, a[0] * nx));
}

// s (a x b).
template <class Real>
HWY_INLINE void cross_scaled(V<Real> s, const V3<Real>& a, const V3<Real>& b, V3<Real>& out) {
  out[0] = s * fmsub(a[1], b[2], a[2] * b[1]);
  out[1] = s * fmsub(a[2], b[0], a[0] * b[2]);
  out[2] = s * fmsub(a[0], b[1], a[1] * b[0]);
}

// The tet forces f_1..f_3 into f[1..3] and f_0 = -(f_1 + f_2 + f_3), then
// added into the slice's force array.
template <class Real>
HWY_INLINE void scatter_tet(Real* force, const int32_t* const (&q)[4], V3<Real> (&f)[4]) {
  for (int k = 0; k < 3; ++k) f[0][k] = zero<Real>() - (f[1][k] + f[2][k] + f[3][k]);
  for (int i = 0; i < 4; ++i) scatter_add(force, q[i], f[i]);
}

// cof F (rows: cof_ij = (-1)^(i+j) minor of F_ij) and J = det F, for F
// given as I + H.
template <class Real>
HWY_INLINE V<Real> cofactor(const V33<Real>& F, V33<Real>& C) {
  C[0][0] = fmsub(F[1][1], F[2][2], F[1][2] * F[2][1]);
  C[0][1] = fmsub(F[1][2], F[2][0], F[1][0] * F[2][2]);
  C[0][2] = fmsub(F[1][0], F[2][1], F[1][1] * F[2][0]);
  C[1][0] = fmsub(F[0][2], F[2][1], F[0][1] * F[2][2]);
  C[1][1] = fmsub(F[0][0], F[2][2], F[0][2] * F[2][0]);
  C[1][2] = fmsub(F[0][1], F[2][0], F[0][0] * F[2][1]);
  C[2][0] = fmsub(F[0][1], F[1][2], F[0][2] * F[1][1]);
  C[2][1] = fmsub(F[0][2], F[1][0], F[0][0] * F[1][2]);
  C[2][2] = fmsub(F[0][0], F[1][1], F[0][1] * F[1][0]);
  return fmadd(F[0][2], C[0][2], fmadd(F[0][1], C[0][1], F[0][0] * C[0][0]));
}

// force_law::shear_barrier_slope on every lane: -1/J from J_min up, the
// quadratic extension's (J - 2 J_min) / J_min^2 below; inv_j = 1 / max(J,
// J_min), the one division, which the damper shares.
template <class Real>
HWY_INLINE V<Real> barrier_slope(V<Real> J, V<Real> inv_j) {
  const Real jm = static_cast<Real>(force_law::kShearElementMinJ);
  const V<Real> below = (J - splat(2 * jm)) * splat(Real(1) / (jm * jm));
  return select(J >= splat(jm), zero<Real>() - inv_j, below);
}

// P = F + phi'(J) cof F (force_law::shear_stress), F = I + H; also cof F
// and inv_j = 1 / max(J, J_min).
template <class Real>
HWY_INLINE void shear_stress(const V33<Real>& H, V33<Real>& P, V33<Real>& C, V<Real>& inv_j) {
  V33<Real> F;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) F[r][k] = r == k ? H[r][k] + splat(Real(1)) : H[r][k];
  const V<Real> J = cofactor<Real>(F, C);
  inv_j = splat(Real(1)) / hn::Max(J, splat(static_cast<Real>(force_law::kShearElementMinJ)));
  const V<Real> slope = barrier_slope<Real>(J, inv_j);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) P[r][k] = fmadd(slope, C[r][k], F[r][k]);
}

// Position Verlet with drag for the points p0..: d' = (1 - alpha dt) d +
// dt^2 F/m, u' = u + d', into the next buffer and its records. Fixed and
// padding points (1/m = 0) stay put.
template <class Real>
HWY_INLINE void integrate(Data<Real>& D, const KernelStepInputs<Real>& in, int32_t p0,
                                             const V3<Real>& u, const V3<Real>& d, const V3<Real>& rest,
                                             const V3<Real>& f) {
  const int nxt = 1 - D.cur;
  const V<Real> inv_mass = load(&D.inv_mass[p0]);
  const MaskOf<Real> free = inv_mass > zero<Real>();
  const V<Real> w = inv_mass * splat(in.dt2), drag = splat(in.drag);
  V3<Real> nd, nu, nx;
  for (int k = 0; k < 3; ++k) {
    nd[k] = keep(free, fmadd(w, f[k], drag * d[k]));
    nu[k] = u[k] + nd[k];
    nx[k] = rest[k] + nu[k];
    store(&D.u[nxt][k][p0], nu[k]);
    store(&D.d[nxt][k][p0], nd[k]);
  }
  store_records(D.positions(nxt), D.inc[nxt].data(), p0, nx, nd);
  if (!D.urec[nxt].empty()) store_positions(D.urec[nxt].data(), p0, nu, nd);
}

template <class Real, ElementTerm Element, bool Gravity, ToolTerm Tool, bool Sutures>
void chunk_step(Data<Real>& D, const KernelStepInputs<Real>& in, int32_t c, ChunkReaction& partial) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  const int cur = D.cur;
  // Local pointers: the vector stores may alias anything, so pointers
  // read through D would be reloaded after every store.
  const Real* const rec = D.positions(cur);
  const Real* const inc = D.inc[cur].data();
  const int32_t* const other = D.spring_other.data();
  const Real* const spring_rest = D.spring_rest.data();
  const Real* const spring_k = D.spring_k.data();
  const Real* const spring_d = D.spring_d.data();
  for (int32_t g = 0; g < D.groups; ++g) {
    const int32_t p0 = c * D.chunk + g * kLanes;
    V3<Real> u, d, rest, x, f;
    for (int k = 0; k < 3; ++k) {
      u[k] = load(&D.u[cur][k][p0]);
      d[k] = load(&D.d[cur][k][p0]);
      rest[k] = load(&D.rest[k][p0]);
      x[k] = rest[k] + u[k];  // the same x = X + u as in the records
      f[k] = Gravity ? load(&D.mass[p0]) * splat(in.gravity[k]) : zero<Real>();
    }

    // Springs + dampers: f = [k (L - r) + d (dv . l/L) / dt] l/L, l = x_q -
    // x_p (force_law::spring_tension). A suture pulls only
    // (force_law::suture_tension): no force while slack (L <= r), and a
    // closing damper never turns the pull into a push.
    const V<Real> inv_dt = splat(in.inv_dt);
    const int32_t spring_width = D.spring_width[c * D.groups + g];
    for (int32_t j = 0, e = D.spring_offset[c] + g * kLanes; j < spring_width; ++j, e += D.chunk) {
      V3<Real> q, qd, l;
      gather_xd<1>(rec, inc, other + e, q, qd);
      for (int k = 0; k < 3; ++k) l[k] = q[k] - x[k];
      const V<Real> len2 = fmadd(l[2], l[2], fmadd(l[1], l[1], l[0] * l[0]));
      const V<Real> inv = inv_length(len2);
      const V<Real> length = len2 * inv;
      const V<Real> dot = fmadd(qd[2] - d[2], l[2], fmadd(qd[1] - d[1], l[1], (qd[0] - d[0]) * l[0]));
      const V<Real> along = dot * inv * inv_dt;
      const V<Real> stretch = length - load(spring_rest + e);
      const V<Real> k = load(spring_k + e);
      V<Real> tension = fmadd(Sutures ? hn::Abs(k) : k, stretch, load(spring_d + e) * along);
      if constexpr (Sutures) {
        const MaskOf<Real> pulls = hn::And(stretch > zero<Real>(), tension > zero<Real>());
        const MaskOf<Real> suture = k < zero<Real>();
        tension = keep(hn::Or(hn::Not(suture), pulls), tension);
      }
      const V<Real> s = tension * inv;
      for (int kk = 0; kk < 3; ++kk) f[kk] = fmadd(s, l[kk], f[kk]);
    }

    if constexpr (Element != ElementTerm::None) {
      // Tet forces, summed per slice by tet_slice(); slices in order.
      for (int sl = 0; sl < kSlices; ++sl) take_forces(&D.tet_force[sl][4 * static_cast<size_t>(p0)], f);
    }

    if constexpr (Tool != ToolTerm::None) {
      // Few points touch the tool: find them with one compare, then
      // add_tool_force() on those lanes, reaction summed per lane in order.
      MaskOf<Real> touching;
      if constexpr (Tool == ToolTerm::Push) {
        V3<Real> o;
        for (int k = 0; k < 3; ++k) o[k] = x[k] - splat(in.tool_center[k]);
        const V<Real> dist2 = fmadd(o[2], o[2], fmadd(o[1], o[1], o[0] * o[0]));
        // The ball about the centre that holds the tool (the sphere itself
        // for a sphere), with a margin so that no lane the exact test accepts
        // is missed.
        const Real r = in.tool_reach * Real(1.001);
        touching = dist2 < splat(r * r);
      } else {
        touching = nonnegative(tool_lane_flags<Tool>(in) + p0, Real(0));
      }
      if (!hn::AllFalse(Tag<Real>(), touching)) {
        uint8_t bits[(kLanes + 7) / 8] = {};
        hn::StoreMaskBits(Tag<Real>(), touching, bits);
        alignas(64) Real fl[3][kLanes], xl[3][kLanes];
        for (int k = 0; k < 3; ++k) store(fl[k], f[k]), store(xl[k], x[k]);
        for (int l = 0; l < kLanes; ++l) {
          if (!(bits[l / 8] >> (l % 8) & 1)) continue;
          const Real xp[3] = {xl[0][l], xl[1][l], xl[2][l]};
          Real fp[3] = {fl[0][l], fl[1][l], fl[2][l]};
          if (!add_tool_force<Real, Tool>(in, p0 + l, xp, fp, partial)) continue;
          for (int k = 0; k < 3; ++k) fl[k][l] = fp[k];
        }
        for (int k = 0; k < 3; ++k) f[k] = load(fl[k]);
      }
    }
    integrate(D, in, p0, u, d, rest, f);
  }
}

// The nodal term's first pass over one slice's tet pairs: 6 V of both tets
// of each and their sum into pair_det6, from the records at `rec`. pack()
// runs it on the rest records for node_rest, so the rest state gives
// exactly q = 0.
template <class Real>
void nodal_volume_slice(Data<Real>& D, const Real* rec, int slice) {
  constexpr int32_t kLanes = Data<Real>::kLanes, kScale = Data<Real>::kRecord / 4;
  const int32_t end = D.pair_slice_begin[slice + 1];
  for (int32_t b = D.pair_slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    V3<Real> x[5];
    for (int i = 0; i < 5; ++i) gather_x<kScale>(rec, D.pair_v[i].data() + e, x[i]);
    V3<Real> ab, ac, ad, ae, n;
    for (int k = 0; k < 3; ++k) {
      ab[k] = x[1][k] - x[0][k], ac[k] = x[2][k] - x[0][k];
      ad[k] = x[3][k] - x[0][k], ae[k] = x[4][k] - x[0][k];
    }
    cross_scaled<Real>(splat(Real(1)), ab, ac, n);
    const V<Real> first = fmadd(n[2], ad[2], fmadd(n[1], ad[1], n[0] * ad[0]));
    const V<Real> second = zero<Real>() - fmadd(n[2], ae[2], fmadd(n[1], ae[1], n[0] * ae[0]));
    Real* const out = D.pair_det6.data() + 3 * e;
    store(out, first + second);
    store(out + kLanes, first);
    store(out + 2 * kLanes, second);
  }
}

// S of the points of group g of chunk c (one register): the sum of their
// tets' 6 V_t over their tet slots, in slot order (thread-count independent).
template <class Real>
HWY_INLINE V<Real> nodal_volume_sum(const Data<Real>& D, int32_t c, int32_t g) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  V<Real> s = zero<Real>();
  const int32_t width = D.node_entry_width[c * D.groups + g];
  for (int32_t j = 0, e = D.node_entry_offset[c] + g * kLanes; j < width; ++j, e += D.chunk)
    s = s + gather_at(D.pair_det6.data(), D.node_entry.data() + e);
  return s;
}

// The nodal term's second pass, per point of chunk c: q = node_k (S - S_r)
// (force_law::volume_pressure, scaled) into the w of its record for the
// force pass to gather.
template <class Real>
void nodal_pressure_chunk(Data<Real>& D, int32_t c) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  Real* const rec = D.positions(D.cur);
  for (int32_t g = 0; g < D.groups; ++g) {
    const int32_t p0 = c * D.chunk + g * kLanes;
    // The pressure a lane at a time: force_law's functions are compiled
    // for the baseline, so they take numbers, not this target's registers.
    alignas(64) Real volume[kLanes];
    store(volume, nodal_volume_sum(D, c, g));
    for (int32_t l = 0; l < kLanes; ++l)
      rec[Data<Real>::kRecord * static_cast<size_t>(p0 + l) + 3] =
          force_law::volume_pressure(D.node_k[p0 + l], volume[l], D.node_rest[p0 + l]);
  }
}

// The smoothed shear element's first pass, per point of chunk c: its stress
// P(Fbar_p) (force_law::shear_stress) with Fbar_p - I = sum over its slots
// of (u_q - u_p) b^T, into node_stress. From displacements: Fbar = I and
// P = 0 exactly at rest.
template <class Real>
void shear_stress_chunk(Data<Real>& D, int32_t c) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  const Real* const urec = D.urec[D.cur].data();
  const int32_t* const other = D.spring_other.data();
  for (int32_t g = 0; g < D.groups; ++g) {
    const int32_t p0 = c * D.chunk + g * kLanes;
    V3<Real> u;
    for (int k = 0; k < 3; ++k) u[k] = load(&D.u[D.cur][k][p0]);
    V33<Real> H;
    for (auto& row : H)
      for (auto& h : row) h = zero<Real>();
    const int32_t spring_width = D.spring_width[c * D.groups + g];
    for (int32_t j = 0, e = D.spring_offset[c] + g * kLanes; j < spring_width; ++j, e += D.chunk) {
      V3<Real> q;
      gather_x<1>(urec, other + e, q);
      const V<Real> b[3] = {load(&D.spring_b[0][e]), load(&D.spring_b[1][e]), load(&D.spring_b[2][e])};
      for (int r = 0; r < 3; ++r) {
        const V<Real> du = q[r] - u[r];
        for (int k = 0; k < 3; ++k) H[r][k] = fmadd(du, b[k], H[r][k]);
      }
    }
    V33<Real> P, C;
    V<Real> inv_j;
    shear_stress<Real>(H, P, C, inv_j);
    const V<Real> record[kStressRecord] = {P[0][0], P[0][1], P[0][2], P[1][0], P[1][1], P[1][2], P[2][0], P[2][1]};
    store_values<kStressRecord>(D.node_stress.data() + kStressRecord * static_cast<size_t>(p0), record);
    alignas(64) Real p22[kLanes];
    store(p22, P[2][2]);
    Real* const tail = D.stress_tail(D.cur) + Data<Real>::kRecord * static_cast<size_t>(p0);
    for (int l = 0; l < kLanes; ++l) tail[Data<Real>::kRecord * l] = p22[l];
  }
}

// The shear element's forces on corners 1..3 of one tet (core/model/
// shear_element.h): f_i = -A g_i k_t with A = (1 - s) P(F_t) + s Pbar_t +
// (tau / (dt J_d)) (G cof^T + cof G^T) cof, F_t = I + sum_i (u_i - u_0) g_i^T,
// G = sum_i (d_i - d_0) g_i^T = dt Fdot, Pbar_t the mean of the corners'
// smoothed stresses (`corners`: their sum, P_22 last; s = 0 unsmoothed).
// Corner 0's force is minus the sum of the three.
template <class Real, ElementTerm Element>
HWY_INLINE void shear_tet_forces(const Data<Real>& D, const KernelStepInputs<Real>& in,
                                                    const V3<Real>* const (&u)[4], const V3<Real>* const (&d)[4],
                                                    const V3<Real> (&g)[3], V<Real> kt, const V<Real> (&corners)[9],
                                                    V3<Real> (&f)[3]) {
  V33<Real> H, P, C, A;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      H[r][k] = fmadd((*u[3])[r] - (*u[0])[r], g[2][k],
                      fmadd((*u[2])[r] - (*u[0])[r], g[1][k], ((*u[1])[r] - (*u[0])[r]) * g[0][k]));
  V<Real> inv_j;
  shear_stress<Real>(H, P, C, inv_j);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) A[r][k] = splat(D.shear_per_tet) * P[r][k];
  if constexpr (Element == ElementTerm::SmoothedShear) {
    const V<Real> share = splat(D.shear_corners);
    for (int j = 0; j < 9; ++j) A[j / 3][j % 3] = fmadd(share, corners[j], A[j / 3][j % 3]);
  }
  if (D.damped) {
    V33<Real> G, GC;  // G and G cof^T + cof G^T
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        G[r][k] = fmadd((*d[3])[r] - (*d[0])[r], g[2][k],
                        fmadd((*d[2])[r] - (*d[0])[r], g[1][k], ((*d[1])[r] - (*d[0])[r]) * g[0][k]));
    // Symmetric: the upper triangle, mirrored (the same products, so the
    // same bits as computing both).
    for (int r = 0; r < 3; ++r)
      for (int k = r; k < 3; ++k)
        GC[k][r] = GC[r][k] = fmadd(G[r][2], C[k][2], fmadd(G[r][1], C[k][1], G[r][0] * C[k][0])) +
                              fmadd(C[r][2], G[k][2], fmadd(C[r][1], G[k][1], C[r][0] * G[k][0]));
    const V<Real> damper = splat(in.shear_damping) * inv_j;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        A[r][k] = fmadd(damper, fmadd(GC[r][2], C[2][k], fmadd(GC[r][1], C[1][k], GC[r][0] * C[0][k])), A[r][k]);
  }
  const V<Real> minus_kt = zero<Real>() - kt;
  for (int i = 0; i < 3; ++i)
    for (int r = 0; r < 3; ++r)
      f[i][r] = minus_kt * fmadd(A[r][2], g[i][2], fmadd(A[r][1], g[i][1], A[r][0] * g[i][0]));
}

// The shear element over one slice's tet pairs (tet_pairs.h), into its
// force array: per lane the tets (a, b, c, d) and (a, c, b, e), five
// points' displacements, increments and smoothed stresses for two tets, and
// five forces added back where two separate tets would take eight. Both
// tets use a as corner 0, with the shape gradients packed for that order
// (a lone tet has k_t = 0 and g = 0 in its second place: no force).
template <class Real, ElementTerm Element>
void shear_pair_slice(Data<Real>& D, const KernelStepInputs<Real>& in, int slice) {
  constexpr int32_t kLanes = Data<Real>::kLanes, kScale = Data<Real>::kRecord / 4;
  constexpr bool kSmoothed = Element == ElementTerm::SmoothedShear;
  const Real* const rec = D.urec[D.cur].data();
  const Real* const inc = D.inc[D.cur].data();
  Real* const force = D.tet_force[slice].data();
  const int32_t end = D.shear_slice_begin[slice + 1];
  for (int32_t b = D.shear_slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[5] = {D.pair_v[0].data() + e, D.pair_v[1].data() + e, D.pair_v[2].data() + e,
                                 D.pair_v[3].data() + e, D.pair_v[4].data() + e};
    V3<Real> u[5], d[5];
    V<Real> p22[5];  // the corners' smoothed P_22 (simd_records-inl.h: the increment's 4th value)
    for (int i = 0; i < 5; ++i) {
      if (D.damped || kSmoothed)
        gather_xd<kScale>(rec, inc, q[i], u[i], d[i], p22[i]);
      else
        gather_x<kScale>(rec, q[i], u[i]);
    }
    // The smoothed stresses of the shared face's corners, then each tet's sum.
    V<Real> face[9], first[9], second[9];
    if constexpr (kSmoothed) {
      V<Real> row[kStressRecord];
      gather_values<kStressRecord / 4, kStressRecord>(D.node_stress.data(), q[0], row);
      for (int j = 0; j < kStressRecord; ++j) face[j] = row[j];
      for (int i = 1; i < 3; ++i) {
        gather_values<kStressRecord / 4, kStressRecord>(D.node_stress.data(), q[i], row);
        for (int j = 0; j < kStressRecord; ++j) face[j] = face[j] + row[j];
      }
      face[8] = p22[0] + p22[1] + p22[2];
      gather_values<kStressRecord / 4, kStressRecord>(D.node_stress.data(), q[3], row);
      for (int j = 0; j < kStressRecord; ++j) first[j] = face[j] + row[j];
      first[8] = face[8] + p22[3];
      gather_values<kStressRecord / 4, kStressRecord>(D.node_stress.data(), q[4], row);
      for (int j = 0; j < kStressRecord; ++j) second[j] = face[j] + row[j];
      second[8] = face[8] + p22[4];
    }
    V3<Real> g[3], f1[3], f2[3];
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) g[i][k] = load(D.tet_g[3 * i + k].data() + e);
    shear_tet_forces<Real, Element>(D, in, {&u[0], &u[1], &u[2], &u[3]}, {&d[0], &d[1], &d[2], &d[3]}, g,
                                    load(D.tet_shear_k.data() + e), first, f1);  // (a, b, c, d): on b, c, d
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) g[i][k] = load(D.tet2_g[3 * i + k].data() + e);
    shear_tet_forces<Real, Element>(D, in, {&u[0], &u[2], &u[1], &u[4]}, {&d[0], &d[2], &d[1], &d[4]}, g,
                                    load(D.tet2_shear_k.data() + e), second, f2);  // (a, c, b, e): on c, b, e
    V3<Real> fa;
    for (int k = 0; k < 3; ++k) {
      fa[k] = zero<Real>() - (f1[0][k] + f1[1][k] + f1[2][k] + f2[0][k] + f2[1][k] + f2[2][k]);
      f1[0][k] = f1[0][k] + f2[1][k];  // b
      f1[1][k] = f1[1][k] + f2[0][k];  // c
    }
    scatter_add(force, q[0], fa);
    scatter_add(force, q[1], f1[0]);
    scatter_add(force, q[2], f1[1]);
    scatter_add(force, q[3], f1[2]);
    scatter_add(force, q[4], f2[2]);
  }
}

// The volume terms over one slice's tets into its force array. With V =
// e1 . (e2 x e3) / 6, e_i = x_i - x_0, dV/dx_1 = e2 x e3 / 6 (and
// cyclically) and f_0 = -(f_1 + f_2 + f_3). Per tet f_i = k_v (V_r - V)
// dV/dx_i; nodal f_i = -p_t dV/dx_i, p_t the mean of its vertices'
// pressures, whose scaled q the records carry.
template <class Real, ElementTerm Element>
void tet_slice(Data<Real>& D, int slice) {
  constexpr int32_t kLanes = Data<Real>::kLanes, kScale = Data<Real>::kRecord / 4;
  const Real* const rec = D.positions(D.cur);
  Real* const force = D.tet_force[slice].data();
  const int32_t end = D.slice_begin[slice + 1];
  for (int32_t b = D.slice_begin[slice]; b < end; ++b) {
    const size_t e = static_cast<size_t>(b) * kLanes;
    const int32_t* const q[4] = {D.tet_v[0].data() + e, D.tet_v[1].data() + e, D.tet_v[2].data() + e,
                                 D.tet_v[3].data() + e};
    V3<Real> f[4], x0, ev[3];
    V<Real> s;
    if constexpr (Element == ElementTerm::NodalVolume) {
      V<Real> w;
      gather_xw<kScale>(rec, q[0], x0, s);
      for (int i = 0; i < 3; ++i) {
        gather_xw<kScale>(rec, q[i + 1], ev[i], w);
        s = s + w;  // the sum of the four q: -p_t / 6
      }
    } else {
      gather_x<kScale>(rec, q[0], x0);
      for (int i = 0; i < 3; ++i) gather_x<kScale>(rec, q[i + 1], ev[i]);
    }
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) ev[i][k] = ev[i][k] - x0[k];
    if constexpr (Element == ElementTerm::TetVolume)
      s = load(D.tet_k36.data() + e) * (load(D.tet_det_rest.data() + e) - det6<Real>(ev[0], ev[1], ev[2]));
    cross_scaled<Real>(s, ev[1], ev[2], f[1]);  // e2 x e3
    cross_scaled<Real>(s, ev[2], ev[0], f[2]);  // e3 x e1
    cross_scaled<Real>(s, ev[0], ev[1], f[3]);  // e1 x e2
    scatter_tet(force, q, f);
  }
}

template <class Real, ElementTerm Element, bool Gravity, ToolTerm Tool, bool Sutures>
void step_all(Data<Real>& D, const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) {
  const int32_t nchunk = D.nchunk;
  // The passes as worksharing loops, in a parallel region on several
  // threads and on their own on one: libgomp allocates a team for every
  // region, even of one thread, and a haptic tick does not wait on the
  // allocator (CpuBackend.ATickAllocatesNothingOnceSizedOnOneThreadAndTwo).
  // Called inside another parallel region, the loops keep a region of
  // their own, so that they never share out over the caller's team.
  const auto passes = [&] {
    if constexpr (Element == ElementTerm::NodalVolume) {
      // Every nodal volume before any pressure, every pressure before any force.
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, D.positions(D.cur), sl);
#pragma omp for schedule(static)
      for (int32_t c = 0; c < nchunk; ++c) nodal_pressure_chunk(D, c);
    }
    if constexpr (Element == ElementTerm::SmoothedShear) {
      // Every point's smoothed stress before any tet reads it.
#pragma omp for schedule(static)
      for (int32_t c = 0; c < nchunk; ++c) shear_stress_chunk(D, c);
    }
    if constexpr (Element == ElementTerm::ShearElement || Element == ElementTerm::SmoothedShear) {
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) shear_pair_slice<Real, Element>(D, in, sl);
    } else if constexpr (Element != ElementTerm::None) {
#pragma omp for schedule(static)
      for (int sl = 0; sl < kSlices; ++sl) tet_slice<Real, Element>(D, sl);
    }
#pragma omp for schedule(static)
    for (int32_t c = 0; c < nchunk; ++c) {
      ChunkReaction r;
      chunk_step<Real, Element, Gravity, Tool, Sutures>(D, in, c, r);
      if constexpr (Tool != ToolTerm::None) partial[c] = r;
    }
  };
  if (threads > 1 || omp_in_parallel()) {
#pragma omp parallel num_threads(threads)
    passes();
  } else {
    passes();
  }
}

// The plan's choices as template arguments, one level at a time.
template <class Real, ElementTerm Element, bool Gravity, ToolTerm Tool>
void step_sutures(Data<Real>& D, const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) {
  if (D.sutures) step_all<Real, Element, Gravity, Tool, true>(D, in, threads, partial);
  else step_all<Real, Element, Gravity, Tool, false>(D, in, threads, partial);
}

template <class Real, ElementTerm Element, bool Gravity>
void step_tool(Data<Real>& D, const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) {
  switch (in.tool) {
    case ToolTerm::Push: return step_sutures<Real, Element, Gravity, ToolTerm::Push>(D, in, threads, partial);
    case ToolTerm::Pull: return step_sutures<Real, Element, Gravity, ToolTerm::Pull>(D, in, threads, partial);
    case ToolTerm::Surface: return step_sutures<Real, Element, Gravity, ToolTerm::Surface>(D, in, threads, partial);
    case ToolTerm::None: break;
  }
  step_sutures<Real, Element, Gravity, ToolTerm::None>(D, in, threads, partial);
}

template <class Real, ElementTerm Element>
void step_gravity(Data<Real>& D, const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) {
  if (D.gravity) step_tool<Real, Element, true>(D, in, threads, partial);
  else step_tool<Real, Element, false>(D, in, threads, partial);
}

// The records of point p for the state in buffer b.
template <class Real>
void write_record(Data<Real>& D, int b, int32_t p) {
  constexpr int32_t R = Data<Real>::kRecord;
  Real* const x = D.positions(b) + R * static_cast<size_t>(p);
  Real* const i = D.increments(b) + R * static_cast<size_t>(p);
  Real* const u = D.urec[b].empty() ? nullptr : D.urec[b].data() + R * static_cast<size_t>(p);
  for (int k = 0; k < 3; ++k) {
    x[k] = D.rest[k][p] + D.u[b][k][p];
    i[k] = D.d[b][k][p];
    if (u) {
      u[k] = D.u[b][k][p];
      if (R == 8) u[4 + k] = D.d[b][k][p];
    }
  }
  x[3] = i[3] = 0;
  if (u) u[3] = 0;
}

// Rest lengths of the spring slots from the kernel's own arithmetic on the
// rest records at `rec`, so that the rest state is exactly force-free.
template <class Real>
void pack_rest_lengths(Data<Real>& D, const GatherLayout& L, const Real* rec) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  for (size_t e0 = 0; e0 < D.spring_other.size(); e0 += kLanes) {
    const int32_t p0 = point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e0));
    V3<Real> q, l;
    gather_x<1>(rec, &D.spring_other[e0], q);
    for (int k = 0; k < 3; ++k) l[k] = q[k] - load(&D.rest[k][p0]);
    const V<Real> len2 = fmadd(l[2], l[2], fmadd(l[1], l[1], l[0] * l[0]));
    store(&D.spring_rest[e0], len2 * inv_length(len2));
  }
}

// The shear element's tet pairs in batches of kLanes sharing no point, and
// their shape gradients and k_t (Data::tet_g); empty without it.
template <class Real>
void pack_shear_pairs(Data<Real>& D, const Model& model, bool shear) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  const std::vector<TetPair> pairs = shear ? pair_model_tets(model) : std::vector<TetPair>{};
  const TetBatches batches = batch_tet_pairs(pairs, model.npoint(), kLanes, kSlices);
  std::copy(batches.slice_begin.begin(), batches.slice_begin.end(), D.shear_slice_begin);
  const size_t lanes = batches.lane_tet.size();
  if (shear)
    for (auto& v : D.pair_v) v.assign(lanes, 4 * D.npad);  // padding lanes: the zero record at npad
  for (int j = 0; j < 9; ++j) D.tet_g[j].assign(lanes, 0), D.tet2_g[j].assign(lanes, 0);
  D.tet_shear_k.assign(lanes, 0);
  D.tet2_shear_k.assign(lanes, 0);
  // Tet t's gradients of `corners` (its points other than a) into g at lane e.
  auto put = [&](AlignedVector<Real>(&g)[9], int32_t t, std::array<int32_t, 3> corners, size_t e) {
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) g[3 * i + k][e] = static_cast<Real>(shape_gradient_of(model, t, corners[i])[k]);
  };
  for (size_t e = 0; e < lanes; ++e) {
    if (batches.lane_tet[e] < 0) continue;
    const TetPair& pair = pairs[batches.lane_tet[e]];
    for (int k = 0; k < 5; ++k) D.pair_v[k][e] = 4 * pair.v[k];
    put(D.tet_g, pair.first, {pair.v[1], pair.v[2], pair.v[3]}, e);
    D.tet_shear_k[e] = static_cast<Real>(model.tet_shear_k[pair.first]);
    if (pair.second < 0) continue;
    put(D.tet2_g, pair.second, {pair.v[2], pair.v[1], pair.v[4]}, e);
    D.tet2_shear_k[e] = static_cast<Real>(model.tet_shear_k[pair.second]);
  }
}

// The nodal term's tet pairs in batches of kLanes, cut into kSlices runs,
// and each point's entries of their output (Data::node_entry).
template <class Real>
void pack_nodal_entries(Data<Real>& D, const Model& model) {
  constexpr int32_t kLanes = Data<Real>::kLanes;
  const std::vector<TetPair> pairs = pair_model_tets(model);
  const int32_t nbatch = static_cast<int32_t>((pairs.size() + kLanes - 1) / kLanes);
  const size_t lanes = static_cast<size_t>(nbatch) * kLanes;
  for (int sl = 0; sl <= kSlices; ++sl) D.pair_slice_begin[sl] = nbatch * sl / kSlices;
  for (auto& v : D.pair_v) v.assign(lanes, 4 * D.npad);  // padding lanes: the zero record at npad
  D.pair_det6.assign(3 * lanes + kLanes, 0);
  const int32_t zero_entry = static_cast<int32_t>(3 * lanes);
  std::vector<std::vector<int32_t>> entries(static_cast<size_t>(D.npoint));
  for (size_t i = 0; i < pairs.size(); ++i) {
    const TetPair& pair = pairs[i];
    for (int k = 0; k < 5; ++k) D.pair_v[k][i] = 4 * pair.v[k];
    const int32_t sum = static_cast<int32_t>(3 * (i - i % kLanes) + i % kLanes);
    for (int k = 0; k < 3; ++k) entries[pair.v[k]].push_back(sum);
    entries[pair.v[3]].push_back(sum + kLanes);
    if (pair.second >= 0) entries[pair.v[4]].push_back(sum + 2 * kLanes);
  }
  // The springs' layout: chunk c's slot j of point p at offset[c] + j chunk + (p - c chunk).
  D.node_entry_offset.assign(static_cast<size_t>(D.nchunk) + 1, 0);
  D.node_entry_width.assign(static_cast<size_t>(D.nchunk) * D.groups, 0);
  for (int32_t p = 0; p < D.npoint; ++p) {
    int32_t& width = D.node_entry_width[static_cast<size_t>(p / D.chunk) * D.groups + (p % D.chunk) / kLanes];
    width = std::max(width, static_cast<int32_t>(entries[p].size()));
  }
  for (int32_t c = 0; c < D.nchunk; ++c) {
    const auto first = D.node_entry_width.begin() + static_cast<size_t>(c) * D.groups;
    D.node_entry_offset[c + 1] = D.node_entry_offset[c] + *std::max_element(first, first + D.groups) * D.chunk;
  }
  D.node_entry.assign(static_cast<size_t>(D.node_entry_offset[D.nchunk]), zero_entry);
  for (int32_t p = 0; p < D.npoint; ++p) {
    const int32_t c = p / D.chunk;
    for (size_t j = 0; j < entries[p].size(); ++j)
      D.node_entry[D.node_entry_offset[c] + j * D.chunk + (p - c * D.chunk)] = entries[p][j];
  }
}

// 6 V_r of each batch lane's tet, as the tet pass computes it.
template <class Real>
void pack_rest_volumes(Data<Real>& D, const Real* rec) {
  constexpr int32_t kLanes = Data<Real>::kLanes, kScale = Data<Real>::kRecord / 4;
  for (size_t e0 = 0; e0 < D.tet_det_rest.size(); e0 += kLanes) {
    V3<Real> x[4], ev[3];
    for (int i = 0; i < 4; ++i) gather_x<kScale>(rec, &D.tet_v[i][e0], x[i]);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) ev[i][k] = x[i + 1][k] - x[0][k];
    store(&D.tet_det_rest[e0], det6<Real>(ev[0], ev[1], ev[2]));
  }
}

template <class Real>
void set_point(Data<Real>& D, int32_t p, const Real u[3], const Real d[3]) {
  for (int k = 0; k < 3; ++k) {
    D.u[D.cur][k][p] = u[k];
    D.d[D.cur][k][p] = d[k];
  }
  write_record(D, D.cur, p);
}

template <class Real>
void step(Data<Real>& D, const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) {
  switch (D.element) {
    case ElementTerm::NodalVolume: step_gravity<Real, ElementTerm::NodalVolume>(D, in, threads, partial); break;
    case ElementTerm::TetVolume: step_gravity<Real, ElementTerm::TetVolume>(D, in, threads, partial); break;
    case ElementTerm::ShearElement: step_gravity<Real, ElementTerm::ShearElement>(D, in, threads, partial); break;
    case ElementTerm::SmoothedShear: step_gravity<Real, ElementTerm::SmoothedShear>(D, in, threads, partial); break;
    case ElementTerm::None: step_gravity<Real, ElementTerm::None>(D, in, threads, partial); break;
  }
  D.cur = 1 - D.cur;
}

template <class Real>
void pack(Data<Real>& D, const Model& model, const StepPlan& plan) {
  constexpr int32_t kLanes = Data<Real>::kLanes, R = Data<Real>::kRecord;
  const GatherLayout& L = model.layout;
  const int32_t old_npoint = D.npoint;
  D.npoint = model.npoint();
  D.chunk = L.chunk_size;
  D.nchunk = L.nchunk;
  D.groups = L.chunk_size / kLanes;
  D.npad = D.nchunk * D.chunk;
  D.element = plan.element;
  D.gravity = plan.gravity;
  D.sutures = plan.sutures > 0;
  const bool shear = plan.shear(), smoothed = plan.element == ElementTerm::SmoothedShear;
  D.damped = shear && model.shear_damping_time > 0;
  D.shear_per_tet = smoothed ? static_cast<Real>(1 - model.shear_smoothed_share) : Real(1);
  D.shear_corners = smoothed ? static_cast<Real>(model.shear_smoothed_share / 4) : Real(0);
  const size_t n = static_cast<size_t>(D.npad);

  // Points: padding lanes past npoint have no mass and stay at the origin.
  for (int k = 0; k < 3; ++k) {
    D.rest[k].assign(n, 0);
    for (int32_t p = 0; p < D.npoint; ++p) D.rest[k][p] = static_cast<Real>(model.rest_position[p][k]);
  }
  D.mass.assign(n, 0);
  D.inv_mass.assign(n, 0);
  for (int32_t p = 0; p < D.npoint; ++p) {
    D.mass[p] = static_cast<Real>(model.mass[p]);
    D.inv_mass[p] = static_cast<Real>(model.inv_mass[p]);
  }
  // State: kept for the points it held, zero for new ones (the caller sets them).
  for (int b = 0; b < 2; ++b) {
    for (int k = 0; k < 3; ++k) {
      D.u[b][k].resize(n, 0);
      D.d[b][k].resize(n, 0);
      std::fill(D.u[b][k].begin() + std::min(old_npoint, D.npoint), D.u[b][k].end(), Real(0));
      std::fill(D.d[b][k].begin() + std::min(old_npoint, D.npoint), D.d[b][k].end(), Real(0));
    }
    D.rec[b].assign(R * (n + kLanes), 0);
    D.inc[b].assign(Data<Real>::kSplit ? R * (n + kLanes) : 0, 0);
    D.urec[b].assign(shear ? R * (n + kLanes) : 0, 0);
  }
  // The other buffer (overwritten by the next step) holds the rest records
  // while the rest lengths and volumes are computed from them.
  Real* const rec = D.positions(1 - D.cur);
  for (int32_t p = 0; p < D.npad; ++p)
    for (int k = 0; k < 3; ++k) rec[R * static_cast<size_t>(p) + k] = D.rest[k][p];

  // Slots per group of lanes: the widest point of the group.
  D.spring_width.assign(static_cast<size_t>(D.nchunk) * D.groups, 0);
  for (int32_t p = 0; p < D.npoint; ++p) {
    const size_t g = static_cast<size_t>(p / D.chunk) * D.groups + (p % D.chunk) / kLanes;
    D.spring_width[g] = std::max(D.spring_width[g], L.springs.count[p]);
  }
  D.spring_offset.assign(L.springs.chunk_offset.begin(), L.springs.chunk_offset.end());

  // Per-slot streams; padding slots point at their own point with zero
  // stiffness (a zero-length spring and a flat tet add nothing). A suture's
  // stiffness is stored negated (its rest length comes from the schedule,
  // set_spring_rest).
  const size_t ns = L.springs.item.size();
  D.spring_other.resize(ns);
  D.spring_rest.assign(ns, 0);
  D.spring_k.assign(ns, 0);
  D.spring_d.assign(ns, 0);
  for (size_t e = 0; e < ns; ++e) {
    const int32_t s = L.springs.item[e];
    D.spring_other[e] = R * (s < 0 ? point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e)) : L.spring_other[e]);
    if (s < 0) continue;
    D.spring_k[e] = static_cast<Real>(s >= model.first_suture() ? -model.spring_k[s] : model.spring_k[s]);
    D.spring_d[e] = static_cast<Real>(model.spring_d[s]);
  }
  pack_rest_lengths(D, L, rec);

  // Tets in batches of kLanes (see Data and tet_batches.h); the shear
  // element reads them in pairs instead (pack_shear_pairs).
  const TetBatches batches =
      shear ? TetBatches{{}, std::vector<int32_t>(kSlices + 1, 0)} : batch_model_tets(model, kLanes, kSlices);
  std::copy(batches.slice_begin.begin(), batches.slice_begin.end(), D.slice_begin);
  const size_t lanes = batches.lane_tet.size();
  for (auto& v : D.tet_v) v.assign(lanes, 4 * D.npad);  // padding lanes: the zero record at npad
  const size_t per_tet = D.element == ElementTerm::TetVolume ? lanes : 0;
  D.tet_k36.assign(per_tet, 0);
  D.tet_det_rest.assign(per_tet, 0);
  for (size_t e = 0; e < lanes; ++e) {
    const int32_t t = batches.lane_tet[e];
    if (t < 0) continue;
    for (int k = 0; k < 4; ++k) D.tet_v[k][e] = 4 * model.tet_points[t][k];
    if (per_tet) D.tet_k36[e] = static_cast<Real>(model.tet_k[t] / 36);
  }
  pack_shear_pairs(D, model, shear);
  pack_rest_volumes(D, rec);
  for (auto& f : D.tet_force) f.assign(4 * (n + kLanes), 0);
  const bool nodal = D.element == ElementTerm::NodalVolume;
  D.node_k.assign(nodal ? n : 0, 0);
  D.node_rest.assign(D.node_k.size(), 0);
  if (nodal) {
    pack_nodal_entries(D, model);
    for (int32_t p = 0; p < D.npoint; ++p) D.node_k[p] = static_cast<Real>(-model.point_volume_k[p] / 576);
    // S at rest by the step's own passes, so that q is exactly 0 there.
    for (int sl = 0; sl < kSlices; ++sl) nodal_volume_slice(D, rec, sl);
    for (int32_t c = 0; c < D.nchunk; ++c)
      for (int32_t g = 0; g < D.groups; ++g) store(&D.node_rest[c * D.chunk + g * kLanes], nodal_volume_sum(D, c, g));
  }

  // Smoothed shear: b of each slot, sum over the tets of (p, q) of
  // k_t g_q / K_p, and the per-point stress (zero at the padding index npad).
  for (auto& b : D.spring_b) b.assign(smoothed ? ns : 0, 0);
  D.node_stress.assign(smoothed ? kStressRecord * (n + 1) : 0, 0);
  if (smoothed) {
    // The slot of each tet edge (p, q): every tet edge is a spring
    // (Model::first_suture()), so each has one slot at p.
    std::vector<std::map<int32_t, size_t>> slot_of(static_cast<size_t>(D.npoint));
    for (size_t e = 0; e < ns; ++e) {
      if (L.springs.item[e] < 0 || L.springs.item[e] >= model.first_suture()) continue;
      slot_of[point_of_entry(L.springs, D.chunk, static_cast<int32_t>(e))][L.spring_other[e]] = e;
    }
    std::vector<std::array<double, 3>> b(ns, {0, 0, 0});
    for (int32_t t = 0; t < model.ntet(); ++t) {
      const auto& v = model.tet_points[t];
      for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
          if (i == j) continue;
          const size_t e = slot_of[v[i]].at(v[j]);
          const Vec3& g = shape_gradient_of(model, t, v[j]);
          for (int k = 0; k < 3; ++k) b[e][k] += model.tet_shear_k[t] * g[k] / model.point_shear_k[v[i]];
        }
    }
    for (size_t e = 0; e < ns; ++e)
      for (int k = 0; k < 3; ++k) D.spring_b[k][e] = static_cast<Real>(b[e][k]);
  }
  for (int32_t p = 0; p < D.npad; ++p) write_record(D, D.cur, p);
}


// One target's kernel behind the interface the backend holds.
template <class Real>
class Kernel final : public SimdKernel<Real> {
 public:
  explicit Kernel(SimdTarget target) : target_(std::move(target)) {}
  void pack(const Model& model, const StepPlan& plan) override { HWY_NAMESPACE::pack(D_, model, plan); }
  void get_point(int32_t p, Real u[3], Real d[3]) const override {
    for (int k = 0; k < 3; ++k) {
      u[k] = D_.u[D_.cur][k][p];
      d[k] = D_.d[D_.cur][k][p];
    }
  }
  void set_point(int32_t p, const Real u[3], const Real d[3]) override { HWY_NAMESPACE::set_point(D_, p, u, d); }
  const Real* displacement(int k) const override { return D_.u[D_.cur][k].data(); }
  void set_spring_rest(int32_t e, Real rest) override { D_.spring_rest[e] = rest; }
  void step(const KernelStepInputs<Real>& in, int threads, std::vector<ChunkReaction>& partial) override {
    HWY_NAMESPACE::step(D_, in, threads, partial);
  }
  int32_t nchunk() const override { return D_.nchunk; }
  size_t bytes() const override;
  int32_t lanes() const override { return Data<Real>::kLanes; }
  const SimdTarget& target() const override { return target_; }

 private:
  Data<Real> D_;
  SimdTarget target_;
};

template <class Real>
size_t Kernel<Real>::bytes() const {
  const Data<Real>& D = D_;
  size_t n = 0;
  auto add = [&](const auto& v) { n += v.size() * sizeof(v[0]); };
  for (int k = 0; k < 3; ++k) add(D.rest[k]), add(D.spring_b[k]);
  add(D.mass), add(D.inv_mass);
  for (int b = 0; b < 2; ++b) {
    for (int k = 0; k < 3; ++k) add(D.u[b][k]), add(D.d[b][k]);
    add(D.rec[b]), add(D.inc[b]), add(D.urec[b]);
  }
  add(D.spring_other), add(D.spring_rest), add(D.spring_k), add(D.spring_d);
  for (int k = 0; k < 4; ++k) add(D.tet_v[k]);
  for (int k = 0; k < 9; ++k) add(D.tet_g[k]), add(D.tet2_g[k]);
  add(D.tet2_shear_k);
  add(D.node_stress);
  add(D.tet_k36), add(D.tet_det_rest), add(D.tet_shear_k), add(D.node_k), add(D.node_rest);
  for (int k = 0; k < 5; ++k) add(D.pair_v[k]);
  add(D.pair_det6), add(D.node_entry);
  for (const auto& f : D.tet_force) add(f);
  return n;
}

}  // namespace

// This target's kernels (the dispatch table's entries) and its lanes.
SimdKernel<float>* make_kernel_float(const SimdTarget& target) { return new Kernel<float>(target); }
SimdKernel<double>* make_kernel_double(const SimdTarget& target) { return new Kernel<double>(target); }
int32_t float_lanes() { return kLanes<float>; }

}  // namespace organsim::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <cctype>
#include <cstdlib>

#include "core/util/error.h"

namespace organsim {

namespace {

// One compiled target: its bit and its kernels.
struct Entry {
  int64_t bits;
  SimdKernel<float>* (*make_float)(const SimdTarget&);
  SimdKernel<double>* (*make_double)(const SimdTarget&);
  int32_t (*float_lanes)();
};

#define ORGANSIM_ENTRY(TARGET, NS) \
  Entry{TARGET, &NS::make_kernel_float, &NS::make_kernel_double, &NS::float_lanes},

// Best first: the targets compiled here.
const Entry kEntries[] = {ORGANSIM_COMPILED_TARGETS(ORGANSIM_ENTRY)};
#undef ORGANSIM_ENTRY

SimdTarget target_of(int64_t bits) {
  std::string name = hwy::TargetName(bits);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return {bits, name};
}

const Entry& entry_of(const SimdTarget& target) {
  for (const Entry& e : kEntries)
    if (e.bits == target.bits) return e;
  throw Error(ErrorKind::Backend, "simd kernel: target " + target.name + " is not compiled into this binary");
}

std::string names(const std::vector<SimdTarget>& targets) {
  std::string out;
  for (const SimdTarget& t : targets) out += (out.empty() ? "" : ", ") + t.name;
  return out;
}

}  // namespace

std::vector<SimdTarget> simd_targets_compiled() {
  std::vector<SimdTarget> out;
  for (const Entry& e : kEntries) out.push_back(target_of(e.bits));
  return out;
}

std::vector<SimdTarget> simd_targets_supported() {
  std::vector<SimdTarget> out;
  const int64_t supported = hwy::SupportedTargets();
  for (const SimdTarget& t : simd_targets_compiled())
    if ((supported & t.bits) != 0) out.push_back(t);
  return out;
}

SimdTarget simd_target_named(const std::string& name, const std::string& source) {
  const std::vector<SimdTarget> supported = simd_targets_supported();
  if (name == "best") return supported.front();
  for (const SimdTarget& t : simd_targets_compiled()) {
    if (t.name != name) continue;
    if (std::find(supported.begin(), supported.end(), t) == supported.end())
      throw Error(ErrorKind::Input, source + ": this CPU cannot run the " + name + " target (it runs: " +
                                        names(supported) + ")");
    return t;
  }
  throw Error(ErrorKind::Input, source + ": unknown SIMD target '" + name + "' (expected best or one of: " +
                                    names(simd_targets_compiled()) + ")");
}

void set_simd_targets_for_test(int64_t bits) { hwy::SetSupportedTargetsForTest(bits); }

SimdTarget default_simd_target() {
  const char* env = std::getenv("ORGANSIM_SIMD");
  if (env && *env) return simd_target_named(env, "ORGANSIM_SIMD");
  return simd_targets_supported().front();
}

std::string simd_kernel_unsupported(const StepPlan& plan, int32_t chunk_size, const SimdTarget& target) {
  // The passes this kernel runs for the plan's terms: a pass of the plan
  // that is not one of them (a pass added to the step without a kernel for
  // it), or one of them that the plan lacks, is refused by name.
  std::vector<Pass> runs;
  if (plan.element == ElementTerm::NodalVolume) runs.push_back(Pass::NodalPressure);
  if (plan.element == ElementTerm::SmoothedShear) runs.push_back(Pass::ShearSmoothing);
  if (plan.tool == ToolTerm::Surface) runs.push_back(Pass::SurfaceContact);
  runs.push_back(Pass::Springs);
  if (plan.volume()) runs.push_back(Pass::Volume);
  if (plan.shear()) runs.push_back(Pass::ShearElement);
  if (plan.gravity) runs.push_back(Pass::Gravity);
  if (plan.tool != ToolTerm::None) runs.push_back(Pass::ToolContact);
  if (plan.integrator != Integrator::Verlet)
    return std::string("it integrates by position Verlet only (the plan asks ") + integrator_name(plan.integrator) + ")";
  runs.push_back(Pass::Integrate);
  for (Pass pass : plan.passes)
    if (std::find(runs.begin(), runs.end(), pass) == runs.end())
      return std::string("its pass ") + pass_name(pass) + " is not one this kernel runs for the plan's terms";
  for (Pass pass : runs)
    if (!plan.has(pass)) return std::string("it lacks the pass ") + pass_name(pass) + " that its terms need";
  // Float lanes per register: a multiple of the double lanes.
  const int32_t lanes = entry_of(target).float_lanes();
  if (chunk_size % lanes != 0)
    return "layout chunk size " + std::to_string(chunk_size) + " is not a multiple of the " + target.name +
           " target's " + std::to_string(lanes) + " float lanes";
  return "";
}

std::string simd_kernel_unsupported(const Model& model) {
  return simd_kernel_unsupported(make_step_plan(model, BackendTool{}), model.layout.chunk_size, default_simd_target());
}

template <>
std::unique_ptr<SimdKernel<float>> make_simd_kernel(const SimdTarget& target) {
  return std::unique_ptr<SimdKernel<float>>(entry_of(target).make_float(target));
}
template <>
std::unique_ptr<SimdKernel<double>> make_simd_kernel(const SimdTarget& target) {
  return std::unique_ptr<SimdKernel<double>>(entry_of(target).make_double(target));
}

}  // namespace organsim

#endif  // HWY_ONCE
