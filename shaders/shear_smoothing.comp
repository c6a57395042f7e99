// First pass of the smoothed shear element (core/model/shear_element.h):
// each lane owns one point p, gathers its tets from the same table as
// step.comp and writes P(Fbar_p), Fbar_p = I + sum over p's tets of
// (k_t / K_p) (F_t - I), as three columns. step.comp (variant
// SMOOTHED_SHEAR) then reads the stresses of each tet's four vertices, after
// a barrier. F_t - I is built from displacements x - X exactly as step.comp
// builds it, so the rest state has Fbar = I and P = 0 exactly; a point
// without tets (padding, K_p = 0) has only zero weights and writes P(I) = 0.
// THREADS_PER_POINT T: T invocations share a point's tets, as in step.comp.
#ifndef THREADS_PER_POINT
#define THREADS_PER_POINT 1
#endif
layout(local_size_x = ORGANSIM_GL_CHUNK * THREADS_PER_POINT) in;

#include "force_law.glsl"
#include "shear_element.glsl"

struct TetEntry {
  int a, b, c;  // other vertices, (p, a, b, c) positively oriented; p itself for padding
  float k_v;    // unused here (volume terms only)
  float v_r;
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_CHUNKS) readonly buffer Chunks { ivec4 chunks[]; };
layout(std430, binding = ORGANSIM_GL_B_TETS) readonly buffer Tets { TetEntry tets[]; };
layout(std430, binding = ORGANSIM_GL_B_REST) readonly buffer Rest { vec4 rest[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR) readonly buffer Shear { ShearEntry shear[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR_STRESS) writeonly buffer ShearStress { vec4 shear_stress_out[]; };

#if THREADS_PER_POINT > 1
shared mat3 s_partial[ORGANSIM_GL_CHUNK * THREADS_PER_POINT];
#endif

void main() {
  const uint lane = gl_LocalInvocationID.x % ORGANSIM_GL_CHUNK;
  const int part = int(gl_LocalInvocationID.x / ORGANSIM_GL_CHUNK);
  const uint chunk = gl_WorkGroupID.x;
  const int p = int(chunk * ORGANSIM_GL_CHUNK + lane);
  const ivec4 info = chunks[chunk];  // spring offset, spring slots, tet offset, tet slots
  const vec3 up = x_cur[p].xyz - rest[p].xyz;
  mat3 h = mat3(0.0);  // sum of (k_t / K_p) (F_t - I)
  for (int j = part; j < info.w; j += THREADS_PER_POINT) {
    const int slot = info.z + j * ORGANSIM_GL_CHUNK + int(lane);
    const TetEntry e = tets[slot];
    const ShearEntry g = shear[slot];
    h += g.gc.w * shear_displacement_gradient(x_cur[e.a].xyz - rest[e.a].xyz - up,
                                              x_cur[e.b].xyz - rest[e.b].xyz - up,
                                              x_cur[e.c].xyz - rest[e.c].xyz - up, g);
  }
#if THREADS_PER_POINT > 1
  // Invocation 0 adds the others' partial sums in part order (deterministic).
  s_partial[gl_LocalInvocationID.x] = h;
  memoryBarrierShared();
  barrier();
  if (part != 0) return;
  for (int k = 1; k < THREADS_PER_POINT; ++k) h += s_partial[k * ORGANSIM_GL_CHUNK + lane];
#endif
  const mat3 P = shear_stress(mat3(1.0) + h);
  shear_stress_out[3 * p] = vec4(P[0], 0.0);
  shear_stress_out[3 * p + 1] = vec4(P[1], 0.0);
  shear_stress_out[3 * p + 2] = vec4(P[2], 0.0);
}
