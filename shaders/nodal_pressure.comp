// First pass of the averaged nodal volume term (docs/physics.md): each lane
// owns one point, gathers its tets from the same table as step.comp and
// writes its nodal pressure q_p = k_p (V_p - V_p^r), V_p = sum of V_t / 4.
// step.comp (variant NODAL_VOLUME) then reads the pressures of each tet's
// four vertices, after a barrier. The pressure is force_law.glsl's.
// THREADS_PER_POINT T: T invocations share a point's tets, as in step.comp.
#ifndef THREADS_PER_POINT
#define THREADS_PER_POINT 1
#endif
layout(local_size_x = ORGANSIM_GL_CHUNK * THREADS_PER_POINT) in;
#include "force_law.glsl"

struct TetEntry {
  int a, b, c;  // other vertices, (p, a, b, c) positively oriented; p itself for padding
  float k_v;    // unused here (per-tet term only)
  float v_r;
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_CHUNKS) readonly buffer Chunks { ivec4 chunks[]; };
layout(std430, binding = ORGANSIM_GL_B_TETS) readonly buffer Tets { TetEntry tets[]; };
layout(std430, binding = ORGANSIM_GL_B_NODAL) readonly buffer Nodal { vec2 nodal[]; };
layout(std430, binding = ORGANSIM_GL_B_PRESSURE) writeonly buffer Pressure { float pressure[]; };

#if THREADS_PER_POINT > 1
shared float s_partial[ORGANSIM_GL_CHUNK * THREADS_PER_POINT];
#endif

void main() {
  const uint lane = gl_LocalInvocationID.x % ORGANSIM_GL_CHUNK;
  const int part = int(gl_LocalInvocationID.x / ORGANSIM_GL_CHUNK);
  const uint chunk = gl_WorkGroupID.x;
  const int p = int(chunk * ORGANSIM_GL_CHUNK + lane);
  const ivec4 info = chunks[chunk];  // spring offset, spring slots, tet offset, tet slots
  const vec3 xi = x_cur[p].xyz;
  float v = 0.0;
  for (int j = part; j < info.w; j += THREADS_PER_POINT) {
    const TetEntry e = tets[info.z + j * ORGANSIM_GL_CHUNK + int(lane)];
    v += dot(x_cur[e.a].xyz - xi, cross(x_cur[e.b].xyz - xi, x_cur[e.c].xyz - xi)) * (1.0 / 24.0);
  }
#if THREADS_PER_POINT > 1
  s_partial[gl_LocalInvocationID.x] = v;
  memoryBarrierShared();
  barrier();
  if (part != 0) return;
  for (int k = 1; k < THREADS_PER_POINT; ++k) v += s_partial[k * ORGANSIM_GL_CHUNK + lane];
#endif
  const vec2 n = nodal[p];  // {k_p (N/m^5; 0 for padding), V_p^r (m^3)}
  pressure[p] = volume_pressure(n.x, v, n.y);
}
