// First pass of the smoothed shear element (core/model/shear_element.h):
// each lane owns one point, gathers its tets from the same table as
// step.comp and writes P(Fbar_p) = Fbar + phi'(J) cof Fbar, with
// Fbar_p - I = sum over its tets of k_t H_t / K_p and H_t = sum over the
// others q of (u_q - u_p) g_q^T from displacements u = x - X, as step.comp
// builds F - I: at rest H = 0, Fbar = I and P = 0 exactly. step.comp
// (variant SMOOTHED_SHEAR) then reads the stresses of each tet's four
// corners, after a barrier. Same formulas as core/sim/cpu_backend.cpp.
// THREADS_PER_POINT T: T invocations share a point's tets, as in step.comp.
#ifndef THREADS_PER_POINT
#define THREADS_PER_POINT 1
#endif
layout(local_size_x = ORGANSIM_GL_CHUNK * THREADS_PER_POINT) in;

struct TetEntry {
  int a, b, c;  // other vertices; p itself for padding
  float k_v;    // unused here
  float v_r;
};
struct ShearEntry {
  vec4 ga;  // rest gradient of a's barycentric coordinate (1/m), w = k_t (J; 0 for padding)
  vec4 gb;  // b's, w = the damper (unused here)
  vec4 gc;  // c's
};

layout(std430, binding = ORGANSIM_GL_B_X_CUR) readonly buffer XCur { vec4 x_cur[]; };
layout(std430, binding = ORGANSIM_GL_B_CHUNKS) readonly buffer Chunks { ivec4 chunks[]; };
layout(std430, binding = ORGANSIM_GL_B_TETS) readonly buffer Tets { TetEntry tets[]; };
layout(std430, binding = ORGANSIM_GL_B_REST) readonly buffer Rest { vec4 rest[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR) readonly buffer Shear { ShearEntry shear[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR_NODE) readonly buffer ShearNode { float inv_k[]; };
layout(std430, binding = ORGANSIM_GL_B_SHEAR_STRESS) writeonly buffer ShearStress { vec4 stress[]; };

#if THREADS_PER_POINT > 1
shared mat3 s_partial[ORGANSIM_GL_CHUNK * THREADS_PER_POINT];
#endif

void main() {
  const uint lane = gl_LocalInvocationID.x % ORGANSIM_GL_CHUNK;
  const int part = int(gl_LocalInvocationID.x / ORGANSIM_GL_CHUNK);
  const uint chunk = gl_WorkGroupID.x;
  const int p = int(chunk * ORGANSIM_GL_CHUNK + lane);
  const ivec4 info = chunks[chunk];  // spring offset, spring slots, tet offset, tet slots
  const vec3 ui = x_cur[p].xyz - rest[p].xyz;
  mat3 h = mat3(0.0);  // sum of k_t H_t (column-major: outerProduct(du, g) is du g^T)
  for (int j = part; j < info.w; j += THREADS_PER_POINT) {
    const int slot = info.z + j * ORGANSIM_GL_CHUNK + int(lane);
    const TetEntry e = tets[slot];
    const ShearEntry g = shear[slot];
    h += g.ga.w * (outerProduct(x_cur[e.a].xyz - rest[e.a].xyz - ui, g.ga.xyz) +
                   outerProduct(x_cur[e.b].xyz - rest[e.b].xyz - ui, g.gb.xyz) +
                   outerProduct(x_cur[e.c].xyz - rest[e.c].xyz - ui, g.gc.xyz));
  }
#if THREADS_PER_POINT > 1
  s_partial[gl_LocalInvocationID.x] = h;
  memoryBarrierShared();
  barrier();
  if (part != 0) return;
  for (int k = 1; k < THREADS_PER_POINT; ++k) h += s_partial[k * ORGANSIM_GL_CHUNK + lane];
#endif
  const mat3 F = mat3(1.0) + inv_k[p] * h;
  const mat3 cof = mat3(cross(F[1], F[2]), cross(F[2], F[0]), cross(F[0], F[1]));
  const float J = dot(F[0], cof[0]);
  const float jm = 0.5;  // kShearElementMinJ
  const float slope = J >= jm ? -1.0 / J : (J - 2.0 * jm) / (jm * jm);
  const mat3 P = F + slope * cof;
  stress[3 * p] = vec4(P[0], 0.0);
  stress[3 * p + 1] = vec4(P[1], 0.0);
  stress[3 * p + 2] = vec4(P[2], 0.0);
}
