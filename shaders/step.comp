// One position-Verlet substep, fused: each lane owns one point, gathers its
// springs (spring + damper) and, per variant, its tets (volume force), gravity
// and tool contact, then writes x_{t+1}. Chunk = workgroup, so entry
// (slot j, lane l) of chunk c is at chunk offset + j * C + l: neighbouring
// lanes read neighbouring entries. No atomics: every point writes only itself.
// Variants (prepended #defines): HAS_VOLUME (with NODAL_VOLUME: the averaged
// nodal term, pressures from nodal_pressure.comp), SHEAR_ELEMENT (the per-tet
// shear element of nu < 1/4; with SMOOTHED_SHEAR s its node-smoothed share s,
// stresses from shear_smoothing.comp), HAS_GRAVITY, TOOL_PUSH, TOOL_PULL,
// TOOL_SURFACE (the push tool against the surface triangles: each surface
// point sums w_p f over its triangles, each recomputed by its three corners;
// with HERTZ_LAYER each f times its factor from hertz_layer.comp's solve),
// and RECORD_FORCE (tests: also store each point's total force).
// THREADS_PER_POINT T (default 1): T invocations share a point's gathers, slot
// j going to invocation j mod T, and invocation 0 adds the T partial sums in a
// fixed order, then integrates. On a GPU a lane's slots are a chain of
// dependent loads (entry, then neighbour), so the slowest chunk's slot count
// times the memory latency bounds the step; T > 1 divides that chain by T and
// gives each multiprocessor T times more warps to hide it (docs/gl.md).
// The force law is force_law.glsl, the twin of core/physics/force_law.h.
#ifndef THREADS_PER_POINT
#define THREADS_PER_POINT 1
#endif
layout(local_size_x = ORGANSIM_GL_CHUNK * THREADS_PER_POINT) in;

struct SpringEntry {
  int other;   // other end; the point itself for padding (zero length: no force)
  float rest;  // m
  float k;     // N/m; negative for a suture (stiffness -k, tension only)
  float d;     // N s/m
};
struct TetEntry {
  int a, b, c;  // other vertices, (p, a, b, c) positively oriented; p itself for padding
  float k_v;    // N/m^5 (0 for padding)
  float v_r;    // rest volume, m^3
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_D_CUR) readonly buffer DCur { vec4 d_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_X_NEXT) writeonly buffer XNext { vec4 x_next[]; };
layout(std430, binding = ORGANSIM_GL_B_D_NEXT) writeonly buffer DNext { vec4 d_next[]; };
layout(std430, binding = ORGANSIM_GL_B_MASS) readonly buffer Mass { vec4 mass[]; };
layout(std430, binding = ORGANSIM_GL_B_CHUNKS) readonly buffer Chunks { ivec4 chunks[]; };
layout(std430, binding = ORGANSIM_GL_B_SPRINGS) readonly buffer Springs { SpringEntry springs[]; };
#include "force_law.glsl"
#if defined(HAS_VOLUME) || defined(SHEAR_ELEMENT)
layout(std430, binding = ORGANSIM_GL_B_TETS) readonly buffer Tets { TetEntry tets[]; };
#endif
#ifdef SHEAR_ELEMENT
#include "shear_element.glsl"
layout(std430, binding = ORGANSIM_GL_B_REST) readonly buffer Rest { vec4 rest[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR) readonly buffer Shear { ShearEntry shear[]; };
#endif
#ifdef SMOOTHED_SHEAR
layout(std430, binding = ORGANSIM_GL_B_SHEAR_STRESS) readonly buffer ShearStress { vec4 smoothed_stress_in[]; };
// P(Fbar_q) of point q, written by shear_smoothing.comp.
mat3 smoothed_stress(int q) {
  return mat3(smoothed_stress_in[3 * q].xyz, smoothed_stress_in[3 * q + 1].xyz, smoothed_stress_in[3 * q + 2].xyz);
}
#endif
#ifdef NODAL_VOLUME
layout(std430, binding = ORGANSIM_GL_B_PRESSURE) readonly buffer Pressure { float pressure[]; };
#endif
#ifdef TOOL_PULL
layout(std430, binding = ORGANSIM_GL_B_ATTACH) readonly buffer Attach { vec4 attach[]; };
#endif
#ifdef TOOL_SURFACE
layout(std430, binding = ORGANSIM_GL_B_SURFACE) readonly buffer Surface { ivec2 surface_range[]; };
layout(std430, binding = ORGANSIM_GL_B_SURFACE_TRIS) readonly buffer SurfaceTris { ivec4 surface_tris[]; };
#endif
#ifdef FRICTION
layout(std430, binding = ORGANSIM_GL_B_ANCHOR) buffer Anchors { vec4 anchors[]; };  // each point's own
#endif
#ifdef HERTZ_LAYER
layout(std430, binding = ORGANSIM_GL_B_LAYER_OUT) readonly buffer LayerOut { vec4 layer_result; };  // {n, delta}, hertz_layer.comp
#endif
#if defined(TOOL_PUSH) || defined(TOOL_PULL) || defined(TOOL_SURFACE)
layout(std430, binding = ORGANSIM_GL_B_PARTIALS) writeonly buffer Partials { vec4 partials[]; };
#endif
// Fail fast on blow-up without a readback per step: the lowest point whose new
// position is not finite, per tick (ring slot), read back with the reaction.
layout(std430, binding = ORGANSIM_GL_B_STATUS) buffer Status { uint first_non_finite[]; };
layout(location = ORGANSIM_GL_U_SLOT) uniform int u_slot;

#ifdef RECORD_FORCE
layout(std430, binding = ORGANSIM_GL_B_FORCE) writeonly buffer Force { vec4 force_out[]; };
#endif

#if THREADS_PER_POINT > 1
shared vec3 s_partial[ORGANSIM_GL_CHUNK * THREADS_PER_POINT];  // each invocation's gathered force
#endif

layout(location = ORGANSIM_GL_U_DT) uniform float u_dt;
layout(location = ORGANSIM_GL_U_DAMPING) uniform float u_alpha_dt;  // alpha dt
layout(location = ORGANSIM_GL_U_DT2) uniform float u_dt2;           // dt^2
#ifdef HAS_GRAVITY
layout(location = ORGANSIM_GL_U_GRAVITY) uniform vec3 u_gravity;
#endif
#if defined(TOOL_PUSH) || defined(TOOL_PULL) || defined(TOOL_SURFACE)
layout(location = ORGANSIM_GL_U_TOOL_CENTER) uniform vec3 u_tool_center;
layout(location = ORGANSIM_GL_U_TOOL_ACTIVE) uniform int u_tool_active;
layout(location = ORGANSIM_GL_U_TOOL_RADIUS) uniform float u_tool_radius;
layout(location = ORGANSIM_GL_U_TOOL_K) uniform float u_tool_k;
layout(location = ORGANSIM_GL_U_REDUCE) uniform int u_reduce;
#if defined(TOOL_PUSH) || defined(TOOL_SURFACE)
layout(location = ORGANSIM_GL_U_TOOL_A) uniform vec3 u_tool_a;  // the shape's segment (a == b: a sphere)
layout(location = ORGANSIM_GL_U_TOOL_B) uniform vec3 u_tool_b;
#endif
#ifdef GRASPER
layout(location = ORGANSIM_GL_U_TOOL_A2) uniform vec3 u_tool_a2;  // the second jaw
layout(location = ORGANSIM_GL_U_TOOL_B2) uniform vec3 u_tool_b2;
layout(location = ORGANSIM_GL_U_JAW_AXIS) uniform vec3 u_jaw_axis;
#endif
#ifdef FRICTION
layout(location = ORGANSIM_GL_U_FRICTION) uniform vec2 u_friction;  // {mu_s, mu_k}
layout(location = ORGANSIM_GL_U_TOOL_ROTATION) uniform mat3 u_tool_rotation;
#endif

shared vec4 s_force[ORGANSIM_GL_CHUNK];   // {F.xyz, contacts}
shared vec4 s_torque[ORGANSIM_GL_CHUNK];  // {T.xyz, grip}
#endif

void main() {
  // Invocation part * C + lane: a warp's invocations share one part and read
  // consecutive entries of a slot.
  const uint lane = gl_LocalInvocationID.x % ORGANSIM_GL_CHUNK;
  const int part = int(gl_LocalInvocationID.x / ORGANSIM_GL_CHUNK);
  const uint chunk = gl_WorkGroupID.x;
  const int p = int(chunk * ORGANSIM_GL_CHUNK + lane);
  const ivec4 info = chunks[chunk];  // spring offset, spring slots, tet offset, tet slots
  const float inv_dt = 1.0 / u_dt;

  const vec3 xi = x_cur[p].xyz;
  const vec3 di = d_cur[p].xyz;  // x_t - x_{t-1}
  const vec3 vi = di * inv_dt;
  vec3 f = vec3(0.0);

  // Springs + dampers: f = T u with the tension T = k (L - r) + d ((v_q - v_p) . u).
  // A suture (k < 0 in its entry) pulls only.
  for (int j = part; j < info.y; j += THREADS_PER_POINT) {
    const SpringEntry e = springs[info.x + j * ORGANSIM_GL_CHUNK + int(lane)];
    const vec3 xq = x_cur[e.other].xyz;
    const vec3 l = xq - xi;
    const float len = length(l);
    if (len > 0.0) {  // coincident points (and padding): no direction, no force
      const vec3 u = l / len;
      const vec3 dv = d_cur[e.other].xyz * inv_dt - vi;
      const float tension = spring_tension(abs(e.k), e.d, len, e.rest, dot(dv, u));
      f += (e.k < 0.0 ? suture_tension(tension, len, e.rest) : tension) * u;
    }
  }

#ifdef HAS_VOLUME
  // f = -p dV/dx_p, dV/dx_p = (c - a) x (b - a) / 6, with the tet's pressure
  // p = k_v (V - V_r), V = a.(b x c)/6 relative to p, or the mean of its
  // four nodal pressures.
  for (int j = part; j < info.w; j += THREADS_PER_POINT) {
    const TetEntry e = tets[info.z + j * ORGANSIM_GL_CHUNK + int(lane)];
    const vec3 a = x_cur[e.a].xyz - xi;
    const vec3 b = x_cur[e.b].xyz - xi;
    const vec3 c = x_cur[e.c].xyz - xi;
    const vec3 grad = cross(c - a, b - a) * (1.0 / 6.0);
#ifdef NODAL_VOLUME
    f -= tet_pressure_from_nodal(pressure[p], pressure[e.a], pressure[e.b], pressure[e.c]) * grad;
#else
    f -= volume_pressure(e.k_v, dot(a, cross(b, c)) * (1.0 / 6.0), e.v_r) * grad;
#endif
  }
#endif

#ifdef SHEAR_ELEMENT
  // f_p = k_t P(F) s with P(F) = F + phi'(J) cof F, F = I + sum over the
  // others q of (u_q - u_p) g_q^T from displacements u = x - X, s = g_a +
  // g_b + g_c = -g_p (core/model/shear_element.h, shaders/force_law.glsl).
  // Smoothed: k_t [(1 - s_sm) P(F) + s_sm Pbar] s, Pbar the mean of the four
  // vertices' P(Fbar) from shear_smoothing.comp. The damper (full d_t) adds
  // (d_t / (dt J_d)) (G (cof^T c) + cof (G^T c)), c = cof s, G = sum over the
  // others q of (d_q - d_p) g_q^T = dt Fdot, J_d = max(J, J_min).
  const vec3 ui = xi - rest[p].xyz;
#ifdef SMOOTHED_SHEAR
  const mat3 Pp = smoothed_stress(p);
#endif
  for (int j = part; j < info.w; j += THREADS_PER_POINT) {
    const int slot = info.z + j * ORGANSIM_GL_CHUNK + int(lane);
    const TetEntry e = tets[slot];
    const ShearEntry g = shear[slot];
    const mat3 F = mat3(1.0) + shear_displacement_gradient(x_cur[e.a].xyz - rest[e.a].xyz - ui,
                                                           x_cur[e.b].xyz - rest[e.b].xyz - ui,
                                                           x_cur[e.c].xyz - rest[e.c].xyz - ui, g);
    const mat3 cof = shear_cofactor(F);
    const float J = dot(F[0], cof[0]);
    const vec3 s = g.ga.xyz + g.gb.xyz + g.gc.xyz;
    const vec3 c = cof * s;
    const vec3 per_tet = F * s + shear_barrier_slope(J) * c;  // P(F) s
#ifdef SMOOTHED_SHEAR
    const mat3 Pbar = 0.25 * (Pp + smoothed_stress(e.a) + smoothed_stress(e.b) + smoothed_stress(e.c));
    const vec3 elastic = (1.0 - SMOOTHED_SHEAR) * per_tet + SMOOTHED_SHEAR * (Pbar * s);
#else
    const vec3 elastic = per_tet;
#endif
    const mat3 G = outerProduct(d_cur[e.a].xyz - di, g.ga.xyz) + outerProduct(d_cur[e.b].xyz - di, g.gb.xyz) +
                   outerProduct(d_cur[e.c].xyz - di, g.gc.xyz);
    f += g.ga.w * elastic +
         (g.gb.w * inv_dt / max(J, kShearMinJ)) * (G * (transpose(cof) * c) + cof * (transpose(G) * c));
  }
#endif

#if THREADS_PER_POINT > 1
  // Invocation 0 of each point adds the others' partial sums in part order
  // (deterministic). Every invocation reaches every barrier (uniform flow);
  // only invocation 0 contributes to the reaction and writes the point.
  s_partial[gl_LocalInvocationID.x] = f;
  memoryBarrierShared();
  barrier();
  if (part == 0) {
    for (int k = 1; k < THREADS_PER_POINT; ++k) f += s_partial[k * ORGANSIM_GL_CHUNK + lane];
  }
#endif
  const bool owner = part == 0;

  const vec4 m = mass[p];  // {1/m, m, tool stiffness scale s, s / surface triangles of p (0 off the surface)}
#ifdef HAS_GRAVITY
  f += m.y * u_gravity;
#endif

#if defined(TOOL_PUSH) || defined(TOOL_PULL) || defined(TOOL_SURFACE)
  vec4 contact_force = vec4(0.0);   // reaction on the tool {-f.xyz, 1}
  vec4 contact_torque = vec4(0.0);  // (x - c) x (-f)
  // Padding lanes (m = 0) sit on a real point's position: they must not touch the tool.
  if (owner && u_tool_active != 0 && m.y > 0.0) {
    const vec3 d = xi - u_tool_center;
#if defined(TOOL_PUSH)
    // Penalty contact inside the sphere, the point's share m.z of k_c.
    vec3 fc;
    if (push_penalty(xi - segment_closest_point(xi, u_tool_a, u_tool_b), u_tool_radius, u_tool_k * m.z, fc)) {
      f += fc;
      contact_force = vec4(-fc, 1.0);
      contact_torque = vec4(cross(d, -fc), 0.0);
    }
#elif defined(TOOL_SURFACE)
    // Surface contact: w_p(t) f(t) over the point's triangles in ascending
    // order and jaw by jaw (the CPU's surface-contact pass sums them in the
    // same order), after the broad phase (the tool's segments' box against
    // the triangle's box).
    const ivec2 range = surface_range[p];
    vec3 fc = vec3(0.0);
    bool touching = false;
    const float r2 = u_tool_radius * u_tool_radius;
#ifdef GRASPER
    const int jaws = 2;
    const vec3 seg_a[2] = vec3[2](u_tool_a, u_tool_a2), seg_b[2] = vec3[2](u_tool_b, u_tool_b2);
    const vec3 seg_lo = min(min(u_tool_a, u_tool_b), min(u_tool_a2, u_tool_b2));
    const vec3 seg_hi = max(max(u_tool_a, u_tool_b), max(u_tool_a2, u_tool_b2));
    const vec3 closing[2] = vec3[2](-u_jaw_axis, u_jaw_axis);
    float grip = 0.0;  // this point's share of the jaws' closing forces
#else
    const int jaws = 1;
    const vec3 seg_a[1] = vec3[1](u_tool_a), seg_b[1] = vec3[1](u_tool_b);
    const vec3 seg_lo = min(u_tool_a, u_tool_b), seg_hi = max(u_tool_a, u_tool_b);
#endif
    for (int j = 0; j < range.y; ++j) {
      const ivec4 t = surface_tris[range.x + j];
      const vec3 a = x_cur[t.x].xyz, b = x_cur[t.y].xyz, c = x_cur[t.z].xyz;
      const vec3 out_lo = max(min(min(a, b), c) - seg_hi, vec3(0.0));
      const vec3 out_hi = max(seg_lo - max(max(a, b), c), vec3(0.0));
      const vec3 gap = out_lo + out_hi;
      if (!(dot(gap, gap) < r2)) continue;
      for (int jaw = 0; jaw < jaws; ++jaw) {
        vec3 ft, w;
        const vec3 share = vec3(mass[t.x].w, mass[t.y].w, mass[t.z].w);
        if (capsule_triangle_penalty(seg_a[jaw], seg_b[jaw], u_tool_radius, a, b, c, u_tool_k, share, ft, w)) {
#ifdef HERTZ_LAYER
          // The penalty with the sphere moved back by the layer's offset.
          const float m = length(ft);
          const float k_t = u_tool_k * min(min(share.x, share.y), share.z);
          ft *= hertz_layer_factor(m, k_t, dot(ft, layer_result.xyz) / m, layer_result.w);
#endif
          fc += w[t.w] * ft;
          touching = true;
#ifdef GRASPER
          grip += w[t.w] * dot(ft, closing[jaw]);
#endif
        }
      }
    }
#ifdef FRICTION
    // The point's anchor, kept in the tool's frame (force_law::anchor_friction);
    // w: 0 none, 1 sticking, 2 slipping.
    const vec4 held = anchors[p];
    if (touching) {
      vec3 anchor = held.w > 0.0 ? u_tool_center + u_tool_rotation * held.xyz : xi;
      bool slipping = held.w > 1.5;
      const vec3 normal = fc;
      fc += anchor_friction(xi, normal, u_tool_k * m.z, u_friction.x, u_friction.y, anchor, slipping);
      anchors[p] = vec4(transpose(u_tool_rotation) * (anchor - u_tool_center), slipping ? 2.0 : 1.0);
    } else if (held.w > 0.0) {
      anchors[p] = vec4(0.0);
    }
#endif
#ifdef GRASPER
    contact_torque.w = grip;
#endif
    if (touching) {
      f += fc;
      contact_force = vec4(-fc, 1.0);
      contact_torque.xyz = cross(d, -fc);
    }
#else
    // Grasped points follow centre + offset through springs of stiffness k_c.
    const vec4 at = attach[p];
    if (at.w > 0.0) {
      const vec3 fc = pull_attachment(u_tool_center + at.xyz, xi, u_tool_k * m.z);
      f += fc;
      contact_force = vec4(-fc, 1.0);
      contact_torque = vec4(cross(d, -fc), 0.0);
    }
#endif
  }
  // Last substep of a tick: reduce this workgroup's reaction in shared memory
  // (fixed tree order, deterministic) into one partial; reduce_reaction.comp
  // sums the partials. u_reduce is uniform, so the barriers are in uniform flow.
  if (u_reduce != 0) {
    if (owner) {
      s_force[lane] = contact_force;
      s_torque[lane] = contact_torque;
    }
    memoryBarrierShared();
    barrier();
    for (uint half_size = ORGANSIM_GL_CHUNK / 2; half_size > 0; half_size /= 2) {
      if (owner && lane < half_size) {
        s_force[lane] += s_force[lane + half_size];
        s_torque[lane] += s_torque[lane + half_size];
      }
      memoryBarrierShared();
      barrier();
    }
    if (owner && lane == 0) {
      partials[2 * chunk] = s_force[0];
      partials[2 * chunk + 1] = s_torque[0];
    }
  }
#endif

  if (!owner) return;  // no barrier below
#ifdef RECORD_FORCE
  force_out[p] = vec4(f, 0.0);
#endif
  // Position Verlet with mass-proportional drag, in difference form:
  // d_{t+1} = (1 - alpha dt) d_t + dt^2 f/m, x_{t+1} = x_t + d_{t+1}; the same
  // x_{t+1} = x_t + (1 - alpha dt)(x_t - x_{t-1}) + dt^2 f/m as the CPU, but
  // the velocity never passes through the rounding of absolute positions.
  // Fixed points and padding lanes have 1/m = 0 and stay put.
  // (d - (alpha dt) d rather than (1 - alpha dt) d: in float, 1 - alpha dt
  // keeps alpha dt to only ~6e-8 absolute, i.e. 1e-4 relative at 1e-3.)
  const vec3 d_new = m.x > 0.0 ? (di - u_alpha_dt * di) + (u_dt2 * m.x) * f : vec3(0.0);
  const vec3 x_new = xi + d_new;
  x_next[p] = vec4(x_new, 1.0);
  d_next[p] = vec4(d_new, 0.0);
  // Exponent bits all ones = inf or NaN; bit tests survive any fast-math
  // assumption a compiler might make about isnan(). Rare: one atomic per bad point.
  const uvec3 exponent = floatBitsToUint(x_new) & 0x7f800000u;
  if (any(equal(exponent, uvec3(0x7f800000u)))) atomicMin(first_non_finite[u_slot], uint(p));
}
